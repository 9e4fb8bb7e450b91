//! The cones of directions in which a point can lie from its nearest point on the mesh, bounded
//! by the normals around each vertex: what tells `scan.rs` where the points nearest to a vertex
//! lie, and the level set which nearest triangles sign a point by their own normal.
//!
//! A point `p` at distance `d` from the mesh whose nearest point `q` lies inside a face is
//! straight above it. If `q` lies on an edge, `p − q` lies between the normals of the edge's
//! two faces, on the side of `p`. If `q` is a vertex, `p − q` makes at least 90° with each of
//! its edges; for a closed fan whose faces all make less than 90° with an axis `a` at the
//! vertex, every direction square to the axis runs along the fan somewhere, so `p − q` lies
//! within the fan's widest angle to `a` (its spread) of `a` or of `−a`, on the side of `p`
//! (Bærentzen & Aanæs's pseudonormal argument, bounded by the spread). Either way `p − q` makes
//! at most `γ = max over corners v of (∠(n, a_v) + spread_v)` with `±n`, for the normal `n` of
//! any face holding `q`: below 90°, the sign of `(p − q) · n` is the side of `p`.

use glam::Vec3;

use crate::data::TriMesh;
use crate::mesh::{area_weighted_normals, unit_normal};

/// Each vertex's axis and the spread of its faces' normals about it.
pub(super) struct Cones {
    /// The normalised sum of the vertex's faces' area-weighted normals (zero if they cancel).
    axis: Vec<Vec3>,
    /// The least cosine between the axis and the unit normal of one of the vertex's faces
    /// (0 or less: a fan that does not lie on one side of a plane, or a degenerate face).
    spread: Vec<f32>,
}

impl Cones {
    pub(super) fn new(mesh: &TriMesh) -> Cones {
        let axis = area_weighted_normals(&mesh.vertices, &mesh.triangles);
        let mut spread = vec![1.0f32; mesh.vertices.len()];
        for t in &mesh.triangles {
            let n = unit_normal(t, &mesh.vertices);
            for &v in t {
                let s = &mut spread[v as usize];
                *s = s.min(n.dot(axis[v as usize]));
            }
        }
        Cones { axis, spread }
    }

    /// Vertex `v`'s axis and the cosine of its faces' widest angle to it, None where that
    /// reaches 90°: a point nearest to `v` lies within that angle of the axis, on one side.
    pub(super) fn cap(&self, v: u32) -> Option<(Vec3, f32)> {
        let (axis, cos) = (self.axis[v as usize], self.spread[v as usize]);
        (cos > 0.0 && axis != Vec3::ZERO).then_some((axis, cos))
    }

    /// Whether γ stays below 90° for triangle `t` of unit normal `n` (see the module's
    /// comment): not at a sharp corner, a fold or a degenerate face.
    pub(super) fn narrow(&self, t: [u32; 3], n: Vec3) -> bool {
        t.into_iter().all(|v| {
            let (ca, cb) = (n.dot(self.axis[v as usize]), self.spread[v as usize]);
            // cos(α + β) > 0, with cos α and cos β positive: α + β below 90°.
            ca > 0.0 && cb > 0.0 && ca * cb - sine(ca) * sine(cb) > 0.0
        })
    }
}

fn sine(cos: f32) -> f32 {
    (1.0 - cos * cos).max(0.0).sqrt()
}
