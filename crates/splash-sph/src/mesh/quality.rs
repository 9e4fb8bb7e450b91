//! Render quality of a surface mesh, the figures of issue 25 ([`Quality`], with their
//! definitions).

use glam::DVec3;
use rayon::prelude::*;

use super::topology::{component_volumes, signed_volume, topology};
use super::{TriMesh, self_intersecting_faces};

/// A triangle whose smallest angle is below this many degrees is a sliver.
pub const SLIVER_DEGREES: f64 = 10.0;
/// Components of at most this many triangles count as small (floaters).
pub const SMALL_COMPONENT_FACES: usize = 20;

/// The render figures of one mesh (issue 25): volume error against the particles' own volume
/// N·r³, bumpiness (dihedral angles), sliver share, closedness and small components.
///
/// Definitions (each sum in `f64`, in fixed chunks: the same mesh gives the same bits on any
/// number of threads):
/// - **volume error** = V / (N·r³) − 1, V the mesh's signed volume: incompressible SPH keeps
///   each particle's volume r³, so N·r³ is the fluid's volume ([`volume_error`]).
/// - **bumpiness** = Σₑ θₑ·wₑ / Σₑ wₑ over the edges e shared by exactly two non-degenerate
///   triangles, θₑ the angle between their face normals in degrees and wₑ the mean of their
///   two areas: an area-weighted mean dihedral angle, 0 on a plane, which falls as a smooth
///   surface is sampled more finely and rises with every ripple.
/// - **slivers** = share of the triangles whose smallest interior angle is under 10°
///   (degenerate triangles, with a repeated vertex or no area, count as slivers).
/// - **self-intersecting faces** = faces that cross, touch or overlap another face of the mesh
///   beyond the corners they share, by the exact test of [`self_intersecting_faces`]: 0 for a
///   surface that is the boundary of a solid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quality {
    /// Triangles.
    pub faces: usize,
    /// Vertices.
    pub vertices: usize,
    /// Signed enclosed volume.
    pub volume: f64,
    /// Area-weighted mean dihedral angle, degrees (see the definition above).
    pub bumpiness: f64,
    /// Share of triangles with an angle under [`SLIVER_DEGREES`], in [0, 1].
    pub slivers: f64,
    /// Every edge shared by exactly two triangles winding it in opposite directions.
    pub closed_manifold: bool,
    /// Connected components (vertex connectivity).
    pub components: usize,
    /// Components of at most [`SMALL_COMPONENT_FACES`] triangles.
    pub small_components: usize,
    /// Faces crossing another face of the mesh ([`self_intersecting_faces`]).
    pub self_intersecting_faces: usize,
}

/// V / (N·r³) − 1: the volume's error against `particles` of spacing `spacing`.
pub fn volume_error(volume: f64, particles: usize, spacing: f32) -> f64 {
    volume / (particles as f64 * f64::from(spacing).powi(3)) - 1.0
}

/// The figures of `mesh`.
pub fn quality(mesh: &TriMesh) -> Quality {
    let top = topology(mesh);
    let small_components = component_volumes(mesh)
        .iter()
        .filter(|(faces, _)| *faces <= SMALL_COMPONENT_FACES)
        .count();
    Quality {
        faces: mesh.triangles.len(),
        vertices: mesh.vertices.len(),
        volume: signed_volume(mesh),
        bumpiness: bumpiness(mesh),
        slivers: sliver_share(mesh),
        closed_manifold: top.is_closed_manifold(),
        components: top.components,
        small_components,
        self_intersecting_faces: self_intersecting_faces(&mesh.vertices, &mesh.triangles).len(),
    }
}

fn corners(mesh: &TriMesh, t: &[u32; 3]) -> [DVec3; 3] {
    t.map(|i| mesh.vertices[i as usize].as_dvec3())
}

/// Twice-area normal of a triangle.
fn area_normal(p: [DVec3; 3]) -> DVec3 {
    (p[1] - p[0]).cross(p[2] - p[0])
}

/// The smallest interior angle of a triangle, degrees; 0 when it has no area.
pub fn smallest_angle(p: [DVec3; 3]) -> f64 {
    let mut smallest = f64::INFINITY;
    for i in 0..3 {
        let (a, b) = (p[(i + 1) % 3] - p[i], p[(i + 2) % 3] - p[i]);
        // atan2 of |a×b| and a·b: accurate for the tiny angles that decide a sliver.
        let angle = a.cross(b).length().atan2(a.dot(b));
        smallest = smallest.min(angle);
    }
    if smallest.is_finite() {
        smallest.to_degrees()
    } else {
        0.0
    }
}

/// Share of `mesh`'s triangles whose smallest angle is under [`SLIVER_DEGREES`]; 0 without
/// triangles.
pub fn sliver_share(mesh: &TriMesh) -> f64 {
    if mesh.triangles.is_empty() {
        return 0.0;
    }
    let slivers = mesh
        .triangles
        .par_iter()
        .filter(|t| {
            t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || {
                smallest_angle(corners(mesh, t)) < SLIVER_DEGREES
            }
        })
        .count();
    slivers as f64 / mesh.triangles.len() as f64
}

/// The area-weighted mean dihedral angle of `mesh` in degrees (module docs); 0 when no edge
/// is shared by two triangles. Edges of one, or of three and more, triangles are left out.
pub fn bumpiness(mesh: &TriMesh) -> f64 {
    // One (edge, triangle) key per triangle side, sorted: the two triangles of an edge meet.
    // Key = min << 33 | max << 1 (room for 2^31 vertices), then the triangle's index.
    let mut sides: Vec<(u64, u32)> = mesh
        .triangles
        .par_iter()
        .enumerate()
        .flat_map_iter(|(i, t)| {
            let degenerate = t[0] == t[1] || t[1] == t[2] || t[0] == t[2];
            (0..3).filter(move |_| !degenerate).map(move |k| {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let (lo, hi) = (a.min(b), a.max(b));
                ((u64::from(lo) << 33) | (u64::from(hi) << 1), i as u32)
            })
        })
        .collect();
    sides.par_sort_unstable();
    let starts: Vec<usize> = (0..sides.len())
        .into_par_iter()
        .filter(|&i| i == 0 || sides[i - 1].0 != sides[i].0)
        .collect();
    let (weighted, weights) = starts
        .par_chunks(1 << 14)
        .enumerate()
        .map(|(chunk, group_starts)| {
            let mut sums = (0.0f64, 0.0f64);
            for (k, &s) in group_starts.iter().enumerate() {
                let global = chunk * (1 << 14) + k;
                let end = starts.get(global + 1).copied().unwrap_or(sides.len());
                if end - s != 2 {
                    continue;
                }
                let n = [sides[s].1, sides[s + 1].1]
                    .map(|f| area_normal(corners(mesh, &mesh.triangles[f as usize])));
                let (l0, l1) = (n[0].length(), n[1].length());
                if l0 == 0.0 || l1 == 0.0 {
                    continue;
                }
                let angle = n[0].cross(n[1]).length().atan2(n[0].dot(n[1])).to_degrees();
                // Mean of the two areas (each half its cross product's length).
                let w = 0.25 * (l0 + l1);
                sums.0 += angle * w;
                sums.1 += w;
            }
            sums
        })
        .collect::<Vec<_>>()
        .into_iter()
        .fold((0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
    if weights > 0.0 {
        weighted / weights
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// The unit icosahedron subdivided `levels` times, projected onto the unit sphere.
    pub(crate) fn icosphere(levels: u32) -> TriMesh {
        let t = (1.0 + 5f32.sqrt()) / 2.0;
        let mut v: Vec<Vec3> = [
            [-1.0, t, 0.0],
            [1.0, t, 0.0],
            [-1.0, -t, 0.0],
            [1.0, -t, 0.0],
            [0.0, -1.0, t],
            [0.0, 1.0, t],
            [0.0, -1.0, -t],
            [0.0, 1.0, -t],
            [t, 0.0, -1.0],
            [t, 0.0, 1.0],
            [-t, 0.0, -1.0],
            [-t, 0.0, 1.0],
        ]
        .map(|p| Vec3::from_array(p).normalize())
        .to_vec();
        let mut f: Vec<[u32; 3]> = vec![
            [0, 11, 5],
            [0, 5, 1],
            [0, 1, 7],
            [0, 7, 10],
            [0, 10, 11],
            [1, 5, 9],
            [5, 11, 4],
            [11, 10, 2],
            [10, 7, 6],
            [7, 1, 8],
            [3, 9, 4],
            [3, 4, 2],
            [3, 2, 6],
            [3, 6, 8],
            [3, 8, 9],
            [4, 9, 5],
            [2, 4, 11],
            [6, 2, 10],
            [8, 6, 7],
            [9, 8, 1],
        ];
        for _ in 0..levels {
            let mut mid = std::collections::HashMap::new();
            let mut next = Vec::new();
            for tri in &f {
                let m = [0, 1, 2].map(|k| {
                    let (a, b) = (tri[k], tri[(k + 1) % 3]);
                    *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                        v.push(((v[a as usize] + v[b as usize]) / 2.0).normalize());
                        v.len() as u32 - 1
                    })
                });
                next.extend([
                    [tri[0], m[0], m[2]],
                    [tri[1], m[1], m[0]],
                    [tri[2], m[2], m[1]],
                    [m[0], m[1], m[2]],
                ]);
            }
            f = next;
        }
        TriMesh {
            normals: v.clone(),
            vertices: v,
            triangles: f,
        }
    }

    /// The unit cube [0, 1]³, two triangles per face, outward.
    pub(crate) fn cube() -> TriMesh {
        let vertices = (0..8)
            .map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32))
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let triangles = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        TriMesh {
            vertices,
            normals: Vec::new(),
            triangles,
        }
    }

    #[test]
    fn a_fine_icosphere_has_the_balls_volume_and_small_bumpiness_and_no_slivers() {
        let mesh = icosphere(5);
        let q = quality(&mesh);
        assert!(q.closed_manifold);
        assert_eq!((q.faces, q.components, q.small_components), (20480, 1, 0));
        let ball = 4.0 / 3.0 * std::f64::consts::PI;
        assert!((q.volume / ball - 1.0).abs() < 2e-3, "{}", q.volume / ball);
        // Neighbouring faces of near-equilateral triangles of edge ℓ on the unit sphere have
        // centroids ℓ/√3 apart, and their normals differ by that angle (radians).
        let edges: Vec<f32> = mesh
            .triangles
            .iter()
            .flat_map(|t| {
                (0..3).map(|k| {
                    (mesh.vertices[t[k] as usize] - mesh.vertices[t[(k + 1) % 3] as usize]).length()
                })
            })
            .collect();
        let mean_edge = edges.iter().sum::<f32>() as f64 / edges.len() as f64;
        let expected = (mean_edge / 3f64.sqrt()).to_degrees();
        assert!(
            (q.bumpiness / expected - 1.0).abs() < 0.05,
            "{} vs {expected}",
            q.bumpiness
        );
        // Halving the edges halves the angles.
        let finer = bumpiness(&icosphere(6));
        assert!((finer / q.bumpiness - 0.5).abs() < 0.02, "{finer}");
        assert_eq!(q.slivers, 0.0);
    }

    #[test]
    fn a_cubes_bumpiness_is_its_edges_right_angles_weighted_by_area() {
        // 18 edges: 12 cube edges at 90°, 6 diagonals at 0°, every triangle of area 1/2.
        let b = bumpiness(&cube());
        assert!((b - 90.0 * 12.0 / 18.0).abs() < 1e-9, "{b}");
        let q = quality(&cube());
        assert!(q.closed_manifold);
        assert!((q.volume - 1.0).abs() < 1e-12);
        assert_eq!((q.components, q.small_components), (1, 1));
        assert!((volume_error(q.volume, 8, 0.5) - 0.0).abs() < 1e-12);
    }

    #[test]
    fn slivers_are_counted_by_their_smallest_angle() {
        let deg = |a: f64| {
            // A triangle with angles a, 90°, 90° − a.
            [
                DVec3::ZERO,
                DVec3::X,
                DVec3::new(1.0, a.to_radians().tan(), 0.0),
            ]
        };
        for a in [1.0, 9.9, 10.1, 30.0, 45.0] {
            assert!((smallest_angle(deg(a)) - a).abs() < 1e-9, "{a}");
        }
        let vertices = [
            DVec3::ZERO,
            DVec3::X,
            DVec3::new(1.0, 0.1, 0.0),
            DVec3::Y,
            DVec3::ONE,
        ]
        .map(|p| p.as_vec3())
        .to_vec();
        let mesh = TriMesh {
            vertices,
            normals: Vec::new(),
            // A 5.7° sliver, a right isosceles triangle, two with a repeated vertex.
            triangles: vec![[0, 1, 2], [0, 1, 3], [0, 0, 1], [0, 1, 1]],
        };
        assert!((sliver_share(&mesh) - 0.75).abs() < 1e-12);
        assert_eq!(smallest_angle([DVec3::ZERO, DVec3::X, 2.0 * DVec3::X]), 0.0);
    }
}
