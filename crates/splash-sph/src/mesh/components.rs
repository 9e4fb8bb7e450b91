//! Removal of small connected components ("floaters": spray droplets): components by vertex
//! connectivity (union-find), enclosed volume by the divergence theorem.

use super::TriMesh;
use super::stars::{compact, validate};
use super::topology::UnionFind;
use crate::error::{Error, Result};

/// The connected component of each triangle (vertex connectivity, as in
/// [`super::topology::Topology::components`]), numbered by first triangle, and their count.
pub(crate) fn triangle_components(mesh: &TriMesh) -> (Vec<u32>, usize) {
    let mut uf = UnionFind::new(mesh.vertices.len());
    for t in &mesh.triangles {
        uf.union(t[0], t[1]);
        uf.union(t[0], t[2]);
    }
    let mut number = vec![u32::MAX; mesh.vertices.len()];
    let mut count = 0;
    let labels = mesh
        .triangles
        .iter()
        .map(|t| {
            let root = uf.find(t[0]) as usize;
            if number[root] == u32::MAX {
                number[root] = count;
                count += 1;
            }
            number[root]
        })
        .collect();
    (labels, count as usize)
}

/// [`triangle_components`]' labels with each component's signed volume (positive for a closed,
/// outward-wound one), by the divergence theorem.
pub(crate) fn component_labels_and_volumes(mesh: &TriMesh) -> (Vec<u32>, Vec<f64>) {
    let (labels, count) = triangle_components(mesh);
    let mut volumes = vec![0.0f64; count];
    for (t, &label) in mesh.triangles.iter().zip(&labels) {
        let [a, b, c] = t.map(|i| mesh.vertices[i as usize].as_dvec3());
        volumes[label as usize] += a.dot(b.cross(c)) / 6.0;
    }
    (labels, volumes)
}

/// Removes the connected components of `mesh` whose enclosed volume is smaller in magnitude
/// than `min_volume` (the command line's `--min-component V` passes `V r³`), and the vertices
/// only they used; returns the rest, vertices and normals in their order, and how many
/// components went.
///
/// A component's volume is the signed volume of its triangles (positive for a closed,
/// outward-wound one); its magnitude is compared so that a small cavity inside the fluid,
/// whose surface winds inward, goes like a small droplet: that fills the cavity.
///
/// Errors: a negative or non-finite `min_volume`, or a mesh that references missing vertices.
pub fn drop_small_components(mesh: &TriMesh, min_volume: f64) -> Result<(TriMesh, usize)> {
    if !(min_volume.is_finite() && min_volume >= 0.0) {
        return Err(Error::Config(format!(
            "smallest component volume must be a non-negative volume, not {min_volume}"
        )));
    }
    validate(mesh)?;
    let (labels, volumes) = component_labels_and_volumes(mesh);
    let keep: Vec<bool> = volumes.iter().map(|v| v.abs() >= min_volume).collect();
    let dropped = keep.iter().filter(|&&k| !k).count();
    if dropped == 0 {
        return Ok((mesh.clone(), 0));
    }
    let triangles: Vec<[u32; 3]> = mesh
        .triangles
        .iter()
        .zip(&labels)
        .filter(|(_, l)| keep[**l as usize])
        .map(|(t, _)| *t)
        .collect();
    Ok((compact(&mesh.vertices, &mesh.normals, &triangles), dropped))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::topology::{component_volumes, topology};
    use crate::{Config, Length, Reconstructor, Vec3};

    /// Particles on a lattice of spacing `r` within `radius` of `centre`.
    fn ball(centre: Vec3, radius: f32, r: f32) -> Vec<Vec3> {
        let n = (radius / r).ceil() as i32;
        let mut out = Vec::new();
        for x in -n..=n {
            for y in -n..=n {
                for z in -n..=n {
                    let p = Vec3::new(x as f32, y as f32, z as f32) * r;
                    if p.length() <= radius {
                        out.push(centre + p);
                    }
                }
            }
        }
        out
    }

    #[test]
    fn one_particle_droplet_goes_fifty_seven_particle_ball_stays() {
        let r = 0.1;
        let single = vec![Vec3::new(5.0, 0.0, 0.0)];
        let fifty = ball(Vec3::ZERO, 2.3 * r, r);
        assert_eq!(fifty.len(), 57, "lattice ball size changed");
        let particles = [single, fifty].concat();
        let config = Config {
            spacing: Some(r),
            cell: Length::parse("r/2").unwrap(),
            // The field's exact isosurface, whose droplet is swollen (the default post-processing
            // gives it r³: tests/post/shapes.rs).
            post: crate::mesh::post::PostConfig {
                raw: true,
                ..Default::default()
            },
            ..Config::default()
        };
        let mesh = Reconstructor::new(config)
            .unwrap()
            .reconstruct(&particles)
            .unwrap()
            .mesh;
        let volumes = component_volumes(&mesh);
        assert_eq!(volumes.len(), 2, "{volumes:?}");
        let r3 = f64::from(r).powi(3);
        // The raw SSP07 surface inflates the lone particle to 3.6 r³ (issue 25) and gives the
        // ball 28 r³: 5 r³ lies between.
        let droplet = volumes[1].1 / r3;
        assert!((3.0..5.0).contains(&droplet), "{droplet}");
        let (out, dropped) = drop_small_components(&mesh, 5.0 * r3).unwrap();
        assert_eq!(dropped, 1);
        let kept = component_volumes(&out);
        assert_eq!(kept.len(), 1);
        assert!(kept[0].1 > 20.0 * r3, "{kept:?}");
        let t = topology(&out);
        assert!(t.is_closed_manifold());
        assert_eq!(t.unused_vertices, 0);
        assert_eq!(out.normals.len(), out.vertices.len());
        // The kept vertices are the big ball's, with their normals, in order.
        let big: Vec<Vec3> = mesh
            .vertices
            .iter()
            .copied()
            .filter(|v| v.x < 2.5)
            .collect();
        assert_eq!(out.vertices, big);
        // Nothing below the threshold: the mesh is returned as it was.
        let (same, none) = drop_small_components(&mesh, 0.01 * r3).unwrap();
        assert_eq!((same, none), (mesh.clone(), 0));
        assert!(drop_small_components(&mesh, f64::NAN).is_err());
    }
}
