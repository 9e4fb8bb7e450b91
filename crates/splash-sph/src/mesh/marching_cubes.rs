//! Marching Cubes cases (Lorensen & Cline 1987), generated from one rule instead of a typed-in
//! table: on every cube face, inside corners are never joined across the face diagonal.
//!
//! Two cubes sharing a face see the same corner signs there, so they cut the face with the same
//! segments, traversed in opposite directions. Every mesh edge on a face is therefore shared by
//! exactly two triangles with opposite winding: a closed, edge-manifold, consistently oriented
//! surface wherever all cells crossing it are triangulated.
//!
//! Corner `c` of a cell sits at offset `(c & 1, c >> 1 & 1, c >> 2 & 1)`. Edge `4a + k` is
//! parallel to axis `a`; bit 0 of `k` is the offset on the lower other axis, bit 1 on the higher.
//! A corner is inside where the field is negative.

use std::sync::LazyLock;

use glam::{IVec3, Vec3};

/// The vertex where the surface crosses the grid edge from `p0` along `axis` (of length
/// `cell`) whose ends have field values `v0` and `v1` of opposite signs: linear interpolation,
/// `t` of the way along. Every engine places its vertices with it, so their meshes agree.
pub fn edge_crossing(p0: Vec3, axis: usize, cell: f32, v0: f32, v1: f32) -> (Vec3, f32) {
    let t = v0 / (v0 - v1);
    let mut p = p0;
    p[axis] += t * cell;
    (p, t)
}

/// The unit normal at a crossing `t` of the way from the end gradients `g0` to `g1`; where
/// they cancel, the edge's direction towards its outside (positive) end.
pub fn crossing_normal(g0: Vec3, g1: Vec3, t: f32, axis: usize, v0: f32, v1: f32) -> Vec3 {
    g0.lerp(g1, t)
        .try_normalize()
        .unwrap_or(IVec3::AXES[axis].as_vec3() * (v1 - v0).signum())
}

/// Offset of corner `c` along each axis.
pub const fn corner_offset(c: usize) -> [usize; 3] {
    [c & 1, (c >> 1) & 1, (c >> 2) & 1]
}

/// The steps to the neighbouring cubes across the faces of a cube that the surface crosses
/// (a face with corners both inside and outside `values`), in the order −x, +x, −y, +y, −z,
/// +z: where surface following goes next.
pub fn crossed_faces(values: &[f32; 8]) -> impl Iterator<Item = IVec3> + '_ {
    (0..3).flat_map(move |axis| {
        [false, true].into_iter().filter_map(move |high| {
            let face = (0..8).filter(|&c| (corner_offset(c)[axis] == 1) == high);
            let (mut inside, mut outside) = (false, false);
            for c in face {
                inside |= values[c] < 0.0;
                outside |= values[c] >= 0.0;
            }
            (inside && outside).then(|| IVec3::AXES[axis] * if high { 1 } else { -1 })
        })
    })
}

/// The two corners of edge `e`, the lower one first.
pub const fn edge_corners(e: usize) -> (usize, usize) {
    let axis = e / 4;
    let (b, c) = other_axes(axis);
    let low = ((e & 1) << b) | (((e >> 1) & 1) << c);
    (low, low | (1 << axis))
}

/// Axis of edge `e`.
pub const fn edge_axis(e: usize) -> usize {
    e / 4
}

const fn other_axes(axis: usize) -> (usize, usize) {
    match axis {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    }
}

fn edge_between(c0: usize, c1: usize) -> usize {
    let (lo, hi) = (c0.min(c1), c0.max(c1));
    let axis = (hi ^ lo).trailing_zeros() as usize;
    let (b, c) = other_axes(axis);
    4 * axis + ((lo >> b) & 1) + (((lo >> c) & 1) << 1)
}

/// Triangles of one case, as edge indices, wound counter-clockwise seen from outside.
#[derive(Clone, Copy, Debug)]
pub struct Case {
    len: u8,
    triangles: [[u8; 3]; 10],
}

impl Case {
    pub fn triangles(&self) -> &[[u8; 3]] {
        &self.triangles[..self.len as usize]
    }
}

/// Case index of a cell from its corner values: bit `c` set when corner `c` is inside.
#[inline]
pub fn case_index(values: &[f32; 8]) -> usize {
    values
        .iter()
        .enumerate()
        .fold(0, |acc, (c, &v)| acc | (usize::from(v < 0.0) << c))
}

/// The 256 cases.
pub fn cases() -> &'static [Case; 256] {
    static CASES: LazyLock<[Case; 256]> = LazyLock::new(|| {
        let mut cases = [Case {
            len: 0,
            triangles: [[0; 3]; 10],
        }; 256];
        for (index, case) in cases.iter_mut().enumerate() {
            *case = build_case(index);
        }
        cases
    });
    &CASES
}

/// Corners of each face in counter-clockwise order seen from outside the cube.
fn face_cycles() -> [[usize; 4]; 6] {
    let mut faces = [[0; 4]; 6];
    for axis in 0..3 {
        // (axis, u, v) is a right-handed frame, so (0,0),(1,0),(1,1),(0,1) in (u,v) turns
        // counter-clockwise about +axis; the face on the low side is seen from −axis.
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        for side in 0..2 {
            let mut cycle =
                [(0, 0), (1, 0), (1, 1), (0, 1)].map(|(a, b)| (side << axis) | (a << u) | (b << v));
            if side == 0 {
                cycle.reverse();
            }
            faces[2 * axis + side] = cycle;
        }
    }
    faces
}

/// Whether edges `a` and `b` lie on a common face of the cube.
fn share_face(a: usize, b: usize) -> bool {
    let (a0, a1) = edge_corners(a);
    let (b0, b1) = edge_corners(b);
    (0..3).any(|axis| {
        let side = |c: usize| c >> axis & 1;
        let s = side(a0);
        [a1, b0, b1].iter().all(|&c| side(c) == s)
    })
}

/// Triangulates a polygon of edge crossings so that no diagonal joins two crossings on one
/// face: such a diagonal would also be an edge of the neighbouring cell's triangles there and
/// make the surface non-manifold. Diagonals inside the cube belong to this cell alone.
fn split_polygon(polygon: &[usize], out: &mut Vec<[u8; 3]>) -> bool {
    let n = polygon.len();
    if n < 3 {
        return n == 2 || n == 0;
    }
    let allowed = |i: usize, j: usize| {
        j - i == 1 || (i == 0 && j == n - 1) || !share_face(polygon[i], polygon[j])
    };
    let mark = out.len();
    // The triangle on side (0, n−1) has its apex k; the rest splits into [0..=k] and [k..n].
    for k in 1..n - 1 {
        if !allowed(0, k) || !allowed(k, n - 1) {
            continue;
        }
        out.push([polygon[0], polygon[k], polygon[n - 1]].map(|e| e as u8));
        if split_polygon(&polygon[..=k], out) && split_polygon(&polygon[k..], out) {
            return true;
        }
        out.truncate(mark);
    }
    false
}

fn build_case(index: usize) -> Case {
    let inside = |c: usize| index >> c & 1 == 1;
    // next[e]: the crossing that follows crossing e along its polygon.
    let mut next = [usize::MAX; 12];
    for cycle in face_cycles() {
        for i in 0..4 {
            let (a, b) = (cycle[i], cycle[(i + 1) % 4]);
            if inside(a) || !inside(b) {
                continue;
            }
            // Entering an inside run at corner b; follow it to where it leaves.
            let mut j = (i + 1) % 4;
            while inside(cycle[(j + 1) % 4]) {
                j = (j + 1) % 4;
            }
            next[edge_between(a, b)] = edge_between(cycle[j], cycle[(j + 1) % 4]);
        }
    }
    let mut case = Case {
        len: 0,
        triangles: [[0; 3]; 10],
    };
    let mut visited = [false; 12];
    for start in 0..12 {
        if next[start] == usize::MAX || visited[start] {
            continue;
        }
        let mut polygon = Vec::with_capacity(12);
        let mut e = start;
        while !visited[e] {
            visited[e] = true;
            polygon.push(e);
            e = next[e];
        }
        // Joining each run's entry to its exit along the faces' counter-clockwise order winds
        // the polygon counter-clockwise seen from the outside region.
        let mut triangles = Vec::with_capacity(polygon.len() - 2);
        assert!(
            split_polygon(&polygon, &mut triangles),
            "case {index}: no triangulation keeps its diagonals off the faces"
        );
        for t in triangles {
            case.triangles[case.len as usize] = t;
            case.len += 1;
        }
    }
    case
}

#[cfg(test)]
mod tests {
    use super::*;

    fn edge_point(e: usize) -> [f32; 3] {
        let (c0, c1) = edge_corners(e);
        let (a, b) = (corner_offset(c0), corner_offset(c1));
        [0, 1, 2].map(|k| (a[k] + b[k]) as f32 / 2.0)
    }

    fn normal(t: &[u8; 3]) -> [f32; 3] {
        let [a, b, c] = t.map(|e| edge_point(e as usize));
        let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ]
    }

    #[test]
    fn edges_join_corners_one_axis_apart() {
        for e in 0..12 {
            let (a, b) = edge_corners(e);
            assert_eq!(a ^ b, 1 << edge_axis(e));
            assert_eq!(edge_between(a, b), e);
        }
    }

    #[test]
    fn single_inside_corner_gives_one_outward_triangle() {
        for c in 0..8 {
            let case = &cases()[1 << c];
            assert_eq!(case.triangles().len(), 1);
            let n = normal(&case.triangles()[0]);
            let away = corner_offset(c).map(|o| 0.5 - o as f32);
            assert!(
                n[0] * away[0] + n[1] * away[1] + n[2] * away[2] > 0.0,
                "corner {c}"
            );
        }
    }

    #[test]
    fn every_crossed_edge_is_used_and_closed_within_the_cell() {
        for (index, case) in cases().iter().enumerate() {
            let crossed: Vec<usize> = (0..12)
                .filter(|&e| {
                    let (a, b) = edge_corners(e);
                    (index >> a & 1) != (index >> b & 1)
                })
                .collect();
            let mut used = [false; 12];
            for t in case.triangles() {
                for &e in t {
                    used[e as usize] = true;
                }
            }
            let used: Vec<usize> = (0..12).filter(|&e| used[e]).collect();
            assert_eq!(used, crossed, "case {index}");
        }
        assert_eq!(cases()[0].triangles().len(), 0);
        assert_eq!(cases()[255].triangles().len(), 0);
    }

    /// Edges used by exactly one triangle of the case, with their direction.
    fn rim(case: &Case) -> Vec<(usize, usize)> {
        let mut directed = Vec::new();
        for t in case.triangles() {
            for k in 0..3 {
                directed.push((t[k] as usize, t[(k + 1) % 3] as usize));
            }
        }
        let rim: Vec<_> = directed
            .iter()
            .copied()
            .filter(|&(a, b)| !directed.contains(&(b, a)))
            .collect();
        assert_eq!(
            rim.len() + 2 * (directed.len() - rim.len()) / 2,
            directed.len()
        );
        rim
    }

    #[test]
    fn neighbours_cut_their_shared_face_alike_with_opposite_winding() {
        for axis in 0..3 {
            let on_face = |c: usize, side: usize| c >> axis & 1 == side;
            for a in 0..256 {
                for b in 0..256 {
                    // A's corners on its high face are B's on its low face.
                    if (0..8).any(|c| on_face(c, 1) && (a >> c & 1) != (b >> (c ^ (1 << axis)) & 1))
                    {
                        continue;
                    }
                    let face_edge = |e: usize, side: usize| {
                        let (c0, c1) = edge_corners(e);
                        on_face(c0, side) && on_face(c1, side)
                    };
                    let to_b = |e: usize| {
                        let (c0, c1) = edge_corners(e);
                        edge_between(c0 ^ (1 << axis), c1 ^ (1 << axis))
                    };
                    let mut from_a: Vec<_> = rim(&cases()[a])
                        .into_iter()
                        .filter(|&(p, q)| face_edge(p, 1) && face_edge(q, 1))
                        .map(|(p, q)| (to_b(q), to_b(p)))
                        .collect();
                    let mut from_b: Vec<_> = rim(&cases()[b])
                        .into_iter()
                        .filter(|&(p, q)| face_edge(p, 0) && face_edge(q, 0))
                        .collect();
                    from_a.sort();
                    from_b.sort();
                    assert_eq!(from_a, from_b, "axis {axis}, cases {a} and {b}");
                }
            }
        }
    }

    #[test]
    fn two_cells_sharing_an_ambiguous_face_cut_it_the_same_way() {
        // Corners 0 and 3 inside: the x = 0 ... z = 0 face is ambiguous. Each inside corner gets
        // its own triangle; a neighbour seeing the same face signs separates them too.
        let case = &cases()[0b0000_1001];
        assert_eq!(case.triangles().len(), 2);
    }
}
