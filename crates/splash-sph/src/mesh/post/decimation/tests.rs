use super::quadric::Quadric;
use super::witness::Surface;
use super::*;
use crate::mesh::components::triangle_components;
use crate::mesh::post::PostConfig;
use crate::mesh::topology::{signed_volume, topology};
use crate::tests::post::shapes::at_spacing;
use rustc_hash::FxHashMap;

/// Distance from `p` to the triangle `t` the long way, independently of the code under
/// test: the projection onto the plane when it falls inside (barycentric signs), else the
/// nearest of the three edges.
fn slow_distance(p: DVec3, t: [DVec3; 3]) -> f64 {
    let n = (t[1] - t[0]).cross(t[2] - t[0]);
    if n.length() > 0.0 {
        let n = n.normalize();
        let q = p - n * n.dot(p - t[0]);
        let inside = (0..3).all(|i| (t[(i + 1) % 3] - t[i]).cross(q - t[i]).dot(n) >= 0.0);
        if inside {
            return (p - q).length();
        }
    }
    (0..3)
        .map(|i| {
            let (a, b) = (t[i], t[(i + 1) % 3]);
            let s = ((p - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
            let s = if s.is_finite() { s } else { 0.0 };
            (p - (a + s * (b - a))).length()
        })
        .fold(f64::INFINITY, f64::min)
}

/// The largest distance of a vertex or a triangle centroid of `decimated` to `original`.
fn max_distance(decimated: &TriMesh, original: &TriMesh) -> f64 {
    let tris: Vec<[DVec3; 3]> = original
        .triangles
        .iter()
        .map(|t| t.map(|v| original.vertices[v as usize].as_dvec3()))
        .collect();
    let centroids = decimated.triangles.iter().map(|t| {
        t.iter()
            .map(|&v| decimated.vertices[v as usize])
            .sum::<Vec3>()
            / 3.0
    });
    let points: Vec<Vec3> = decimated
        .vertices
        .iter()
        .copied()
        .chain(centroids)
        .collect();
    points
        .par_iter()
        .map(|v| {
            let p = v.as_dvec3();
            tris.iter()
                .map(|&t| slow_distance(p, t))
                .fold(f64::INFINITY, f64::min)
        })
        .reduce(|| 0.0, f64::max)
}

/// Euler characteristic of each component, sorted.
fn euler_per_component(mesh: &TriMesh) -> Vec<i64> {
    let (labels, count) = triangle_components(mesh);
    let mut faces = vec![0i64; count];
    let mut edges: Vec<Vec<(u32, u32)>> = vec![Vec::new(); count];
    let mut vertex_label = vec![u32::MAX; mesh.vertices.len()];
    for (t, &l) in mesh.triangles.iter().zip(&labels) {
        faces[l as usize] += 1;
        for i in 0..3 {
            let (a, b) = (t[i], t[(i + 1) % 3]);
            edges[l as usize].push((a.min(b), a.max(b)));
            vertex_label[t[i] as usize] = l;
        }
    }
    let mut out: Vec<i64> = (0..count)
        .map(|l| {
            let e = &mut edges[l];
            e.sort_unstable();
            e.dedup();
            let v = vertex_label.iter().filter(|&&x| x == l as u32).count() as i64;
            v - e.len() as i64 + faces[l]
        })
        .collect();
    out.sort_unstable();
    out
}

/// The default mesh of `particles` at spacing `r`, cell r/2.
fn reconstruct(particles: &[Vec3], r: f32) -> TriMesh {
    at_spacing(particles, r, None, PostConfig::default())
}

/// Particles on a jittered lattice filling a ball and a torus apart from it: two
/// components of genus 0 and 1 with some bumps.
fn ball_and_torus(r: f32) -> Vec<Vec3> {
    let mut next = crate::tests::common::uniform(7);
    let mut out = Vec::new();
    for x in -20..=40 {
        for y in -12..=12 {
            for z in -12..=12 {
                let p = Vec3::new(x as f32, y as f32, z as f32) * r;
                let ball = p.length() <= 8.0 * r;
                let q = p - Vec3::X * 26.0 * r;
                let ring = Vec3::new(q.x, q.y, 0.0).length() - 9.0 * r;
                let torus = ring * ring + q.z * q.z <= (4.0 * r) * (4.0 * r);
                if ball || torus {
                    let jitter = Vec3::new(next(), next(), next()) - 0.5;
                    out.push(p + 0.1 * r * jitter);
                }
            }
        }
    }
    out
}

#[test]
fn error_bound_topology_and_volume_hold() {
    let r = 0.1;
    let mesh = reconstruct(&ball_and_torus(r), r);
    let before = topology(&mesh);
    assert!(before.is_closed_manifold());
    assert_eq!(before.components, 2);
    let max_error = 0.1 * r;
    let out = decimate(&mesh, max_error).unwrap();
    let after = topology(&out);
    assert!(after.is_closed_manifold(), "{after:?}");
    assert_eq!(after.degenerate_triangles, 0);
    assert_eq!(after.unused_vertices, 0);
    assert_eq!(euler_per_component(&out), vec![0, 2]);
    assert_eq!(euler_per_component(&mesh), vec![0, 2]);
    let ratio = out.triangles.len() as f64 / mesh.triangles.len() as f64;
    assert!(
        ratio < 0.5,
        "{} -> {}",
        mesh.triangles.len(),
        out.triangles.len()
    );
    let distance = max_distance(&out, &mesh);
    assert!(distance <= f64::from(max_error), "{distance}");
    let (v0, v1) = (signed_volume(&mesh), signed_volume(&out));
    assert!((v1 / v0 - 1.0).abs() < 0.005, "{v0} -> {v1}");
    assert_eq!(out.normals.len(), out.vertices.len());
    assert_eq!(crate::mesh::topology::normal_agreement(&out), 1.0);
    eprintln!(
        "{} -> {} triangles, largest vertex or centroid distance {distance:.5} of {max_error}, volume {:+.3} %",
        mesh.triangles.len(),
        out.triangles.len(),
        100.0 * (v1 / v0 - 1.0)
    );
}

/// cbd-small frame 40 (a fixture), the splashing frame: decimated at 0.1 r, then clipped
/// by a box cutting it on all six sides, then rid of its droplets under 2 r³; every step
/// closed and manifold, the decimation within its bound and keeping the volume.
#[test]
fn real_frame_through_every_step() {
    let path = crate::tests::common::fixture("frame_0040.ply");
    let particles = crate::io::read_particles(&path, None).unwrap().positions;
    let r = 0.014;
    let mesh = reconstruct(&particles, r);
    let out = decimate(&mesh, 0.1 * r).unwrap();
    let (t0, t1) = (topology(&mesh), topology(&out));
    assert!(t1.is_closed_manifold(), "{t1:?}");
    assert_eq!(euler_per_component(&out), euler_per_component(&mesh));
    assert_eq!(t1.components, t0.components);
    assert!(out.triangles.len() * 10 < mesh.triangles.len());
    let (v0, v1) = (signed_volume(&mesh), signed_volume(&out));
    assert!((v1 / v0 - 1.0).abs() < 1e-4, "{v0} -> {v1}");
    let clipped = crate::mesh::clip_to_box(&out, [0.2, 0.1, 0.1, 1.0, 0.7, 0.7]).unwrap();
    let t = topology(&clipped);
    assert!(
        t.is_closed_manifold() && t.degenerate_triangles == 0,
        "{t:?}"
    );
    assert!(signed_volume(&clipped) > 0.1 * v1 && signed_volume(&clipped) < v1);
    let r3 = f64::from(r).powi(3);
    let (kept, dropped) = crate::mesh::drop_small_components(&clipped, 2.0 * r3).unwrap();
    assert!(dropped > 0);
    assert!(topology(&kept).is_closed_manifold());
    let smallest = crate::mesh::topology::component_volumes(&kept)
        .iter()
        .map(|c| c.1.abs())
        .fold(f64::INFINITY, f64::min);
    assert!(smallest >= 2.0 * r3);
}

#[test]
fn same_mesh_on_one_and_two_threads() {
    let r = 0.1;
    let mesh = reconstruct(&ball_and_torus(r), r);
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| decimate(&mesh, 0.2 * r).unwrap())
    };
    assert_eq!(run(1), run(2));
}

/// The unit cube with each face a `k` × `k` grid of quads, outward.
fn fine_cube(k: u32) -> TriMesh {
    let mut vertices = Vec::new();
    let mut index = FxHashMap::default();
    let mut triangles = Vec::new();
    let mut id = |p: [u32; 3], vertices: &mut Vec<Vec3>| {
        *index.entry(p).or_insert_with(|| {
            vertices.push(Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32) / k as f32);
            vertices.len() as u32 - 1
        })
    };
    for axis in 0..3 {
        for side in [0, k] {
            for i in 0..k {
                for j in 0..k {
                    let corner = |di: u32, dj: u32| {
                        let mut p = [0; 3];
                        p[axis] = side;
                        p[(axis + 1) % 3] = i + di;
                        p[(axis + 2) % 3] = j + dj;
                        p
                    };
                    let q = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)]
                        .map(|p| id(p, &mut vertices));
                    let (t0, t1) = ([q[0], q[1], q[2]], [q[0], q[2], q[3]]);
                    // (axis+1, axis+2) is right-handed about +axis: counter-clockwise seen
                    // from the far side; flip on the near one.
                    if side == k {
                        triangles.extend([t0, t1]);
                    } else {
                        triangles.extend([[t0[0], t0[2], t0[1]], [t1[0], t1[2], t1[1]]]);
                    }
                }
            }
        }
    }
    TriMesh {
        vertices,
        normals: Vec::new(),
        triangles,
    }
}

/// The vertices stay on the faces within 1e-4 (a tenth of the error allowed): the volume
/// constraint and `f32` rounding move the corners by a few 1e-5.
#[test]
fn flat_cube_faces_decimate_to_few_triangles() {
    let mesh = fine_cube(16);
    assert!(topology(&mesh).is_closed_manifold());
    assert!((signed_volume(&mesh) - 1.0).abs() < 1e-6);
    let out = decimate(&mesh, 1e-3).unwrap();
    let t = topology(&out);
    assert!(t.is_closed_manifold());
    assert_eq!(t.euler_characteristic, 2);
    assert!(out.normals.is_empty());
    // The corners hold and every other vertex goes, but for at most one left on an edge of
    // the cube where the greedy order ends with the link condition refusing it (14).
    assert!(out.vertices.len() <= 9, "{}", out.vertices.len());
    assert_eq!(out.triangles.len(), 2 * out.vertices.len() - 4);
    assert!((signed_volume(&out) - 1.0).abs() < 1e-5);
    for v in &out.vertices {
        let on_face = v
            .to_array()
            .iter()
            .any(|&c| c.abs() < 1e-4 || (c - 1.0).abs() < 1e-4);
        let inside = v
            .to_array()
            .iter()
            .all(|&c| (-1e-4..=1.0 + 1e-4).contains(&c));
        assert!(on_face && inside, "{v}");
    }
}

/// The walk finds a witness across the cube from a triangle on another face, exactly within
/// the error, and none for a point just beyond it.
#[test]
fn surface_walk_reaches_the_nearest_face_and_no_farther() {
    let mesh = fine_cube(16);
    let mut stars = Stars::default();
    stars.rebuild(mesh.vertices.len(), &mesh.triangles);
    let max_error = 1e-3;
    let surface = Surface::new(&mesh, stars, max_error);
    let far = (0..mesh.triangles.len() as u32)
        .find(|&t| {
            mesh.triangles[t as usize]
                .iter()
                .all(|&v| mesh.vertices[v as usize].x == 0.0)
        })
        .unwrap();
    let near = DVec3::new(0.93, 0.47, 1.0 + 0.9 * max_error);
    let found = surface.witness(near, [far, far]).unwrap();
    let corners = mesh.triangles[found as usize].map(|v| mesh.vertices[v as usize].as_dvec3());
    assert!(slow_distance(near, corners) <= max_error);
    let beyond = DVec3::new(0.93, 0.47, 1.0 + 1.1 * max_error);
    assert_eq!(surface.witness(beyond, [far, far]), None);
}

/// A quadric kept in f32 at a vertex far from the origin gives back the sum of squared
/// distances to its planes, computed directly, at points around the vertex: to f32's
/// precision of the distances there, not of the coordinates.
#[test]
fn kept_quadrics_measure_small_distances_far_from_the_origin() {
    let p = DVec3::new(40.0, -25.0, 12.5);
    let planes: Vec<(DVec3, f64, f64)> = [
        (DVec3::new(1.0, 2.0, 2.0), 0.3),
        (DVec3::new(-2.0, 1.0, 0.5), 1.7),
        (DVec3::new(0.2, -0.4, 1.0), 0.05),
    ]
    .into_iter()
    .map(|(n, w)| {
        let n = n.normalize();
        // Planes within 1e-3 of the vertex: the errors a decimation weighs.
        let d = -n.dot(p) + 1e-3 * w;
        (n, d, w)
    })
    .collect();
    let q = planes.iter().fold(Quadric::default(), |q, &(n, d, w)| {
        q.add(&Quadric::plane(n, d, w))
    });
    let back = q.kept_at(p).at(p);
    for step in [
        DVec3::ZERO,
        DVec3::new(1e-3, 0.0, 0.0),
        DVec3::new(-2e-3, 1e-3, 3e-3),
    ] {
        let x = p + step;
        let direct: f64 = planes
            .iter()
            .map(|&(n, d, w)| w * (n.dot(x) + d).powi(2))
            .sum();
        let kept = back.eval(x);
        assert!(
            (kept - direct).abs() <= 1e-4 * direct,
            "at {step}: {kept} against {direct}"
        );
    }
    assert_eq!(back.w as f32, q.w as f32);
}

#[test]
fn bad_arguments_are_errors() {
    let mesh = fine_cube(2);
    assert!(decimate(&mesh, 0.0).is_err());
    assert!(decimate(&mesh, f32::NAN).is_err());
    let mut broken = mesh.clone();
    broken.triangles.push([0, 1, 99]);
    assert!(decimate(&broken, 0.1).is_err());
    assert_eq!(
        decimate(&TriMesh::default(), 0.1).unwrap(),
        TriMesh::default()
    );
}
