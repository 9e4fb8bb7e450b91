//! Witnesses: original triangles within the error of a point, found by walking the original
//! mesh towards ever closer triangles.

use glam::{DVec3, Vec3};

use crate::mesh::TriMesh;
use crate::mesh::stars::{DEAD, Stars};

/// The original mesh, for "is this point within the error of the surface" questions answered
/// by walking its triangles: from triangles near the point, over the triangles around their
/// corners, to ever closer ones.
pub(super) struct Surface<'a> {
    vertices: &'a [Vec3],
    triangles: &'a [[u32; 3]],
    stars: Stars,
    max_squared: f64,
}

impl<'a> Surface<'a> {
    /// `mesh` with the triangles around each vertex (`stars`), answering within `max_error`.
    pub(super) fn new(mesh: &'a TriMesh, stars: Stars, max_error: f64) -> Self {
        Surface {
            vertices: &mesh.vertices,
            triangles: &mesh.triangles,
            stars,
            max_squared: max_error * max_error,
        }
    }

    pub(super) fn distance_squared(&self, t: u32, p: DVec3) -> f64 {
        let q = self.triangles[t as usize].map(|v| self.vertices[v as usize].as_dvec3());
        point_triangle_distance_squared(p, q)
    }

    /// An original triangle within the error of `p` (by exact point-to-triangle distance),
    /// found from `hints` by moving to the closest triangle around the corners of the closest
    /// so far while that gets closer; `None` when the walk stops farther away. A `None` may
    /// refuse a point that some farther triangle would have accepted, never the reverse.
    pub(super) fn witness(&self, p: DVec3, hints: [u32; 2]) -> Option<u32> {
        let mut best = (f64::INFINITY, DEAD);
        for h in hints {
            let d = self.distance_squared(h, p);
            if d <= self.max_squared {
                return Some(h);
            }
            if d < best.0 {
                best = (d, h);
            }
        }
        // The stars of the corners the walk's last two triangles share were searched already.
        let mut searched = [DEAD; 3];
        loop {
            let mut next = best;
            let corners = self.triangles[best.1 as usize];
            for v in corners.into_iter().filter(|v| !searched.contains(v)) {
                for &t in self.stars.of(v) {
                    let d = self.distance_squared(t, p);
                    if d <= self.max_squared {
                        return Some(t);
                    }
                    if d < next.0 {
                        next = (d, t);
                    }
                }
            }
            if next.1 == best.1 {
                return None;
            }
            searched = corners;
            best = next;
        }
    }
}

/// Squared distance from `p` to the triangle `t`, through its closest point (Ericson, Real-Time
/// Collision Detection, 5.1.5), computed relative to `p`.
fn point_triangle_distance_squared(p: DVec3, t: [DVec3; 3]) -> f64 {
    let [a, b, c] = t.map(|v| v - p);
    let (ab, ac) = (b - a, c - a);
    // p is the origin now: ap = -a, and so on.
    let d1 = ab.dot(-a);
    let d2 = ac.dot(-a);
    if d1 <= 0.0 && d2 <= 0.0 {
        return a.length_squared();
    }
    let d3 = ab.dot(-b);
    let d4 = ac.dot(-b);
    if d3 >= 0.0 && d4 <= d3 {
        return b.length_squared();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (a + v * ab).length_squared();
    }
    let d5 = ab.dot(-c);
    let d6 = ac.dot(-c);
    if d6 >= 0.0 && d5 <= d6 {
        return c.length_squared();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + w * ac).length_squared();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + w * (c - b)).length_squared();
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    (a + ab * v + ac * w).length_squared()
}
