//! The exact predicates that decide whether two faces meet (see the parent module's header):
//! signs of Shewchuk's `orient3d` and `orient2d` on the corners widened to `f64`.

use glam::DVec3;
use robust::{Coord, Coord3D, orient2d, orient3d};

fn sign(x: f64) -> i8 {
    i8::from(x > 0.0) - i8::from(x < 0.0)
}

/// The side of the plane through `a b c` that `d` lies on (exact; 0: on the plane).
fn side(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> i8 {
    let p = |v: DVec3| Coord3D {
        x: v.x,
        y: v.y,
        z: v.z,
    };
    sign(orient3d(p(a), p(b), p(c), p(d)))
}

/// The orientation of `a b c` seen along axis `k` (the projection dropping coordinate `k`).
pub(super) fn orient2(a: DVec3, b: DVec3, c: DVec3, k: usize) -> i8 {
    let p = |v: DVec3| Coord {
        x: v[(k + 1) % 3],
        y: v[(k + 2) % 3],
    };
    sign(orient2d(p(a), p(b), p(c)))
}

/// An axis along which the non-degenerate triangle `t` has area: its projection along it maps
/// `t`'s plane one to one, so orientations there are those within the plane.
fn projection_axis(t: [DVec3; 3]) -> usize {
    let n = (t[1] - t[0]).cross(t[2] - t[0]).abs();
    let mut axes = [0, 1, 2];
    axes.sort_by(|&i, &j| n[j].total_cmp(&n[i]));
    axes.into_iter()
        .find(|&k| orient2(t[0], t[1], t[2], k) != 0)
        .expect("a non-degenerate triangle has area along some axis")
}

/// Whether two non-degenerate triangles intersect beyond the corners they share (module
/// header).
pub(super) fn faces_meet(p: [DVec3; 3], q: [DVec3; 3]) -> bool {
    // Where each corner of `p` sits in `q`, if anywhere.
    let shared = p.map(|x| q.iter().position(|&y| y == x));
    match shared.iter().flatten().count() {
        0 => disjoint_faces_meet(p, q),
        1 => {
            let i = shared.iter().position(Option::is_some).unwrap_or(0);
            let j = shared[i].unwrap_or(0);
            vertex_sharing_faces_meet(
                p[i],
                [p[(i + 1) % 3], p[(i + 2) % 3]],
                [q[(j + 1) % 3], q[(j + 2) % 3]],
            )
        }
        2 => {
            let i = shared.iter().position(Option::is_none).unwrap_or(0);
            let j = (0..3).find(|&j| !shared.contains(&Some(j))).unwrap_or(0);
            edge_sharing_faces_meet(p[(i + 1) % 3], p[(i + 2) % 3], p[i], q[j])
        }
        // The same triangle twice.
        _ => true,
    }
}

/// Two triangles without a common corner: closed triangles meet iff an edge of one meets the
/// other.
fn disjoint_faces_meet(p: [DVec3; 3], q: [DVec3; 3]) -> bool {
    let sq = q.map(|x| side(p[0], p[1], p[2], x));
    if one_side(sq) {
        return false;
    }
    let sp = p.map(|x| side(q[0], q[1], q[2], x));
    if one_side(sp) {
        return false;
    }
    (0..3).any(|i| {
        let j = (i + 1) % 3;
        segment_meets(p[i], p[j], sp[i], sp[j], q) || segment_meets(q[i], q[j], sq[i], sq[j], p)
    })
}

/// All three strictly on the same side.
fn one_side(s: [i8; 3]) -> bool {
    s[0] != 0 && s[0] == s[1] && s[1] == s[2]
}

/// Triangles `v p₁ p₂` and `v q₁ q₂`, meeting beyond `v` iff the edge opposite `v` in one meets
/// the other.
fn vertex_sharing_faces_meet(v: DVec3, [p1, p2]: [DVec3; 2], [q1, q2]: [DVec3; 2]) -> bool {
    // The other face's far edge strictly on one side of a face's plane: only `v` in common.
    let (s1, s2) = (side(v, p1, p2, q1), side(v, p1, p2, q2));
    if s1 * s2 > 0 {
        return false;
    }
    let (t1, t2) = (side(v, q1, q2, p1), side(v, q1, q2, p2));
    if t1 * t2 > 0 {
        return false;
    }
    segment_meets(p1, p2, t1, t2, [v, q1, q2]) || segment_meets(q1, q2, s1, s2, [v, p1, p2])
}

/// Triangles `a b p` and `b a q`, meeting beyond their edge iff coplanar with `p` and `q` on
/// the same side of it (otherwise their planes meet in the edge's line, which each triangle
/// meets only in the edge).
fn edge_sharing_faces_meet(a: DVec3, b: DVec3, p: DVec3, q: DVec3) -> bool {
    if side(a, b, p, q) != 0 {
        return false;
    }
    let k = projection_axis([a, b, p]);
    orient2(a, b, p, k) == orient2(a, b, q, k)
}

/// Whether the closed segment `d e` meets the closed non-degenerate triangle `t`, `sd` and `se`
/// being the sides of `t`'s plane that `d` and `e` lie on.
fn segment_meets(d: DVec3, e: DVec3, sd: i8, se: i8, t: [DVec3; 3]) -> bool {
    if sd * se > 0 {
        return false;
    }
    if sd == 0 && se == 0 {
        return coplanar_segment_meets(d, e, t);
    }
    // The segment crosses the plane once; there the line through it meets the closed
    // triangle iff it passes no two of its edges on opposite sides.
    let s = [0, 1, 2].map(|i| side(d, e, t[i], t[(i + 1) % 3]));
    !(s.contains(&1) && s.contains(&-1))
}

/// [`segment_meets`] for a segment in the triangle's plane: an end inside the triangle, or the
/// segment meeting one of its edges.
fn coplanar_segment_meets(d: DVec3, e: DVec3, t: [DVec3; 3]) -> bool {
    let k = projection_axis(t);
    let o = orient2(t[0], t[1], t[2], k);
    let inside = |x: DVec3| (0..3).all(|i| orient2(t[i], t[(i + 1) % 3], x, k) * o >= 0);
    inside(d) || inside(e) || (0..3).any(|i| segments_meet(d, e, t[i], t[(i + 1) % 3], k))
}

/// Whether the closed segments `a b` and `c d` of one plane meet, seen along axis `k`, which
/// maps the plane one to one.
fn segments_meet(a: DVec3, b: DVec3, c: DVec3, d: DVec3, k: usize) -> bool {
    let (o1, o2) = (orient2(a, b, c, k), orient2(a, b, d, k));
    let (o3, o4) = (orient2(c, d, a, k), orient2(c, d, b, k));
    if o1 * o2 < 0 && o3 * o4 < 0 {
        return true;
    }
    // Collinear `x` lies on segment `s t` when within its box.
    let on = |s: DVec3, t: DVec3, x: DVec3| {
        (0..3).all(|i| s[i].min(t[i]) <= x[i] && x[i] <= s[i].max(t[i]))
    };
    (o1 == 0 && on(a, b, c))
        || (o2 == 0 && on(a, b, d))
        || (o3 == 0 && on(c, d, a))
        || (o4 == 0 && on(c, d, b))
}
