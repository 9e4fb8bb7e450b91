//! Clipping a closed mesh to a box, plane by plane, each cut capped by a constrained Delaunay
//! triangulation of its cross-section (spade) so that the result stays closed.
//!
//! A plane cuts a closed, consistently wound mesh along closed polylines; the kept part's
//! boundary edges, reversed, bound the cross-section with it on their left (outer loops
//! counter-clockwise, holes clockwise seen from outside the kept side). The constrained
//! triangulation of the rim vertices with these edges as constraints contains every rim edge;
//! its triangles on the left of a rim edge, and those reached from them without crossing one,
//! are the cap, nesting of holes and islands included. Caps of earlier planes are cut like the
//! rest, so box corners need nothing special.

use crate::error::{Error, Result};
use crate::mesh::TriMesh;
use crate::mesh::stars::{compact, validate};
use glam::{DVec3, Vec3};
use rustc_hash::FxHashMap;
use spade::handles::FixedVertexHandle;
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};

/// The part of `mesh` inside `aabb` = `[min x, min y, min z, max x, max y, max z]`, closed by
/// flat caps on the box faces: a closed, manifold, outward mesh stays so, and encloses the
/// volume of its solid intersected with the box. A mesh inside the box comes back unchanged.
///
/// Where vertices lie on a box plane to within a millionth of the mesh's size, that plane is
/// moved out by a few millionths (at most 128) so that no triangle degenerates; the output
/// can then reach that far past the box. Normals of the vertices on a cut are interpolated along the cut
/// edge (the side surface's normals, so a renderer shades the cap's rim smooth).
///
/// Errors: a box with a minimum above its maximum or non-finite bounds, a mesh referencing
/// missing vertices, or a cross-section whose rim touches itself (two rim points equal or a rim
/// edge through a rim point), which a closed mesh without self-intersections does not give.
pub fn clip_to_box(mesh: &TriMesh, aabb: [f32; 6]) -> Result<TriMesh> {
    if aabb.iter().any(|v| !v.is_finite()) || (0..3).any(|i| aabb[i] > aabb[i + 3]) {
        return Err(Error::Config(format!(
            "clipping box {aabb:?} needs finite bounds with each minimum at most its maximum"
        )));
    }
    validate(mesh)?;
    let mut out = mesh.clone();
    for axis in 0..3 {
        for upper in [false, true] {
            let bound = aabb[axis + if upper { 3 } else { 0 }];
            if let Some(cut) = cut(&out, axis, upper, f64::from(bound))? {
                out = cut;
            }
        }
    }
    Ok(out)
}

/// Keeps the part of `mesh` with coordinate `axis` below `bound` (`upper`) or above it, and caps
/// the cut; `None` when nothing lies beyond.
fn cut(mesh: &TriMesh, axis: usize, upper: bool, bound: f64) -> Result<Option<TriMesh>> {
    // Signed distance beyond the plane: positive on the side that goes.
    let sign = if upper { 1.0 } else { -1.0 };
    let beyond = |v: Vec3| sign * (f64::from(v[axis]) - bound);
    let extent = mesh
        .vertices
        .iter()
        .fold(0.0f64, |m, v| m.max(f64::from(v.abs().max_element())));
    let gap = 1e-6 * extent.max(bound.abs()).max(f64::MIN_POSITIVE);
    // Move the plane outwards, by at most 64 steps of two gaps, to where the fewest vertices
    // (none, almost always) lie on it: every edge then crosses it at an interior point, away
    // from its ends.
    let on_plane = |shift: f64| {
        mesh.vertices
            .iter()
            .filter(|&&v| (beyond(v) - shift).abs() < gap)
            .count()
    };
    let mut shift = 0.0;
    let mut fewest = on_plane(0.0);
    for step in 1..=64 {
        if fewest == 0 {
            break;
        }
        let count = on_plane(2.0 * gap * f64::from(step));
        if count < fewest {
            (shift, fewest) = (2.0 * gap * f64::from(step), count);
        }
    }
    let plane = bound + sign * shift;
    let side: Vec<f64> = mesh.vertices.iter().map(|&v| beyond(v) - shift).collect();
    if side.iter().all(|&s| s < 0.0) {
        return Ok(None);
    }

    let mut vertices = mesh.vertices.clone();
    let mut normals = mesh.normals.clone();
    // Rim vertex of each cut edge (lower index first), numbered on first sight.
    let mut rim: FxHashMap<(u32, u32), u32> = FxHashMap::default();
    // The rim points before rounding to `f32`: the cap is triangulated on these, so that
    // crossings a rounding apart (thin fans of an earlier cap, cut near their hub) stay apart.
    let mut exact: Vec<DVec3> = Vec::new();
    let mut crossing = |a: u32, b: u32, vertices: &mut Vec<Vec3>, normals: &mut Vec<Vec3>| {
        let (lo, hi) = (a.min(b), a.max(b));
        *rim.entry((lo, hi)).or_insert_with(|| {
            let (s0, s1) = (side[lo as usize], side[hi as usize]);
            let t = s0 / (s0 - s1);
            let (p0, p1) = (mesh.vertices[lo as usize], mesh.vertices[hi as usize]);
            let mut p = p0.as_dvec3() + t * (p1.as_dvec3() - p0.as_dvec3());
            p[axis] = plane;
            exact.push(p);
            vertices.push(p.as_vec3());
            if !mesh.normals.is_empty() {
                let (n0, n1) = (mesh.normals[lo as usize], mesh.normals[hi as usize]);
                normals.push(n0.lerp(n1, t as f32).normalize_or_zero());
            }
            vertices.len() as u32 - 1
        })
    };
    let mut triangles = Vec::with_capacity(mesh.triangles.len());
    // Rim edges as the cap walks them: the reverse of the kept part's boundary.
    let mut cap_edges: Vec<[u32; 2]> = Vec::new();
    for &t in &mesh.triangles {
        let inside = t.map(|v| side[v as usize] < 0.0);
        match inside.iter().filter(|&&i| i).count() {
            3 => triangles.push(t),
            0 => {}
            1 => {
                let k = inside.iter().position(|&i| i).unwrap();
                let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                let x_ab = crossing(a, b, &mut vertices, &mut normals);
                let x_ca = crossing(c, a, &mut vertices, &mut normals);
                triangles.push([a, x_ab, x_ca]);
                cap_edges.push([x_ca, x_ab]);
            }
            _ => {
                let k = inside.iter().position(|&i| !i).unwrap();
                let (c, a, b) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                let x_bc = crossing(b, c, &mut vertices, &mut normals);
                let x_ca = crossing(c, a, &mut vertices, &mut normals);
                // The quad a b x_bc x_ca, split along its shorter diagonal.
                let d =
                    |i: u32, j: u32| vertices[i as usize].distance_squared(vertices[j as usize]);
                if d(a, x_bc) <= d(b, x_ca) {
                    triangles.extend([[a, b, x_bc], [a, x_bc, x_ca]]);
                } else {
                    triangles.extend([[a, b, x_ca], [b, x_bc, x_ca]]);
                }
                cap_edges.push([x_ca, x_bc]);
            }
        }
    }
    let first_rim = mesh.vertices.len() as u32;
    let cap = triangulate_cap(&exact, &cap_edges, first_rim, axis, upper)?;
    triangles.extend(cap);
    Ok(Some(compact(&vertices, &normals, &triangles)))
}

/// Triangles covering the cross-section bounded by `edges` (indices from `first`, into `rim`),
/// wound so that their normal points along +`axis` for an `upper` plane, −`axis` otherwise.
fn triangulate_cap(
    rim: &[DVec3],
    edges: &[[u32; 2]],
    first: u32,
    axis: usize,
    upper: bool,
) -> Result<Vec<[u32; 3]>> {
    if edges.is_empty() {
        return Ok(Vec::new());
    }
    // Plane coordinates (u, v) with u × v along the outward normal, so that the cross-section
    // lies on the left of its edges and the triangulation's counter-clockwise faces face out.
    let (u, v) = if upper {
        ((axis + 1) % 3, (axis + 2) % 3)
    } else {
        ((axis + 2) % 3, (axis + 1) % 3)
    };
    let points: Vec<Point2<f64>> = rim.iter().map(|p| Point2::new(p[u], p[v])).collect();
    let local: Vec<[usize; 2]> = edges
        .iter()
        .map(|e| e.map(|i| (i - first) as usize))
        .collect();
    let touching = || {
        Error::Input(format!(
            "cannot cap the cut at the box plane {} = {}: the cross-section's rim touches itself",
            ["x", "y", "z"][axis],
            rim[0][axis]
        ))
    };
    let mut conflicts = 0usize;
    let cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::try_bulk_load_cdt(
        points.clone(),
        local.clone(),
        |_| conflicts += 1,
    )
    .map_err(|_| touching())?;
    // Duplicates would renumber the vertices; a rim point on a rim edge would split it.
    if conflicts > 0 || cdt.num_vertices() != rim.len() || cdt.num_constraints() != edges.len() {
        return Err(touching());
    }
    // Faces on the left of a rim edge are in, on its right out; the others take the state of
    // the faces they reach without crossing a rim edge.
    let mut state = vec![0u8; cdt.num_all_faces()]; // 0 unknown, 1 in, 2 out
    let mut queue = Vec::new();
    for e in &local {
        let edge = cdt
            .get_edge_from_neighbors(
                FixedVertexHandle::from_index(e[0]),
                FixedVertexHandle::from_index(e[1]),
            )
            .ok_or_else(touching)?;
        for (face, s) in [(edge.face(), 1u8), (edge.rev().face(), 2u8)] {
            let slot = &mut state[face.fix().index()];
            if (*slot != 0 && *slot != s) || (s == 1 && face.is_outer()) {
                return Err(touching());
            }
            if *slot == 0 && !face.is_outer() {
                *slot = s;
                queue.push(face.fix());
            }
        }
    }
    while let Some(f) = queue.pop() {
        let s = state[f.index()];
        for edge in cdt
            .face(f)
            .as_inner()
            .into_iter()
            .flat_map(|f| f.adjacent_edges())
        {
            if cdt.is_constraint_edge(edge.as_undirected().fix()) {
                continue;
            }
            let next = edge.rev().face();
            if !next.is_outer() && state[next.fix().index()] == 0 {
                state[next.fix().index()] = s;
                queue.push(next.fix());
            }
        }
    }
    Ok(cdt
        .inner_faces()
        .filter(|f| state[f.fix().index()] == 1)
        .map(|f| f.vertices().map(|v| first + v.fix().index() as u32))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::topology::{normal_agreement, signed_volume, topology};
    use std::f32::consts::{PI, TAU};

    /// A latitude-longitude sphere of radius 1 around the origin, outward, with normals.
    fn sphere(rings: u32, segments: u32) -> TriMesh {
        let mut vertices = vec![Vec3::Z];
        for i in 1..rings {
            let theta = PI * i as f32 / rings as f32;
            for j in 0..segments {
                // A twist per ring keeps vertices off the coordinate planes the tests cut.
                let phi = TAU * (j as f32 + 0.37 * i as f32) / segments as f32 + 0.1;
                vertices.push(Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    theta.cos(),
                ));
            }
        }
        vertices.push(Vec3::NEG_Z);
        let ring = |i: u32, j: u32| 1 + (i - 1) * segments + j % segments;
        let south = vertices.len() as u32 - 1;
        let mut triangles = Vec::new();
        for j in 0..segments {
            triangles.push([0, ring(1, j), ring(1, j + 1)]);
            triangles.push([south, ring(rings - 1, j + 1), ring(rings - 1, j)]);
            for i in 1..rings - 1 {
                let (a, b, c, d) = (
                    ring(i, j),
                    ring(i + 1, j),
                    ring(i + 1, j + 1),
                    ring(i, j + 1),
                );
                triangles.extend([[a, b, c], [a, c, d]]);
            }
        }
        let normals = vertices.clone();
        TriMesh {
            vertices,
            normals,
            triangles,
        }
    }

    fn check_closed(mesh: &TriMesh) {
        let t = topology(mesh);
        assert!(t.is_closed_manifold(), "{t:?}");
        assert_eq!(t.degenerate_triangles, 0);
        assert_eq!(t.unused_vertices, 0);
        assert_eq!(mesh.normals.len(), mesh.vertices.len());
    }

    #[test]
    fn sphere_is_checked_closed_and_outward() {
        let s = sphere(64, 128);
        check_closed(&s);
        assert_eq!(topology(&s).euler_characteristic, 2);
        assert!(signed_volume(&s) > 4.1);
    }

    #[test]
    fn half_and_eighth_of_a_sphere() {
        let s = sphere(96, 192);
        let whole = signed_volume(&s);
        let half = clip_to_box(&s, [-2.0, -2.0, -2.0, 2.0, 2.0, 0.0]).unwrap();
        check_closed(&half);
        assert_eq!(topology(&half).euler_characteristic, 2);
        let v = signed_volume(&half);
        assert!(
            (v / (whole / 2.0) - 1.0).abs() < 2e-3,
            "{v} vs {}",
            whole / 2.0
        );
        // The equator lies on the plane z = 0: the plane moves out by two millionths.
        assert!(half.vertices.iter().all(|p| p.z <= 3e-6));
        assert!(half.vertices.iter().any(|p| p.z > 0.0));
        // Three planes through the centre meet at a corner of the box.
        let eighth = clip_to_box(&s, [0.0, 0.0, 0.0, 2.0, 2.0, 2.0]).unwrap();
        check_closed(&eighth);
        let v = signed_volume(&eighth);
        assert!(
            (v / (whole / 8.0) - 1.0).abs() < 5e-3,
            "{v} vs {}",
            whole / 8.0
        );
        assert!(normal_agreement(&eighth) > 0.99);
    }

    #[test]
    fn box_inside_the_sphere_comes_out_as_the_box() {
        // All six caps, each cut again by the later planes along straight lines of collinear
        // rim points.
        let s = sphere(48, 96);
        let b = clip_to_box(&s, [-0.5, -0.4, -0.3, 0.5, 0.4, 0.3]).unwrap();
        check_closed(&b);
        assert_eq!(topology(&b).euler_characteristic, 2);
        let v = signed_volume(&b);
        assert!((v - 0.48).abs() < 1e-5, "{v}");
        for p in &b.vertices {
            assert!(p.abs().cmple(Vec3::new(0.5, 0.4, 0.3) + 1e-5).all(), "{p}");
        }
    }

    #[test]
    fn box_around_the_mesh_changes_nothing_and_box_apart_empties_it() {
        let s = sphere(16, 32);
        assert_eq!(
            clip_to_box(&s, [-1.5, -1.5, -1.5, 1.5, 1.5, 1.5]).unwrap(),
            s
        );
        let none = clip_to_box(&s, [2.0, 2.0, 2.0, 3.0, 3.0, 3.0]).unwrap();
        assert!(none.triangles.is_empty() && none.vertices.is_empty());
        assert!(clip_to_box(&s, [1.0, 0.0, 0.0, 0.0, 1.0, 1.0]).is_err());
    }

    #[test]
    fn torus_cut_through_its_hole_gives_two_capped_pieces() {
        // A plane through a torus's axis cuts it in two rings: two caps, each a disc.
        // Rings half a step off the plane y = 0, so that no vertex lies on the cut.
        let mut torus = crate::tests::common::torus(96, 48, 2.0, 0.6, 0.5);
        torus.normals.clear();
        check_closed_no_normals(&torus);
        let whole = signed_volume(&torus);
        let half = clip_to_box(&torus, [-3.0, 0.0, -3.0, 3.0, 3.0, 3.0]).unwrap();
        check_closed_no_normals(&half);
        let t = topology(&half);
        assert_eq!(t.components, 1);
        assert_eq!(t.euler_characteristic, 2);
        let v = signed_volume(&half);
        assert!(
            (v / (whole / 2.0) - 1.0).abs() < 2e-3,
            "{v} vs {}",
            whole / 2.0
        );
        // A slab through the tube's middle: a plane cutting the torus in two concentric circles
        // gives an annulus cap, a hole nested in an outer loop.
        let slab = clip_to_box(&torus, [-3.0, -3.0, -3.0, 3.0, 3.0, 0.0]).unwrap();
        check_closed_no_normals(&slab);
        assert_eq!(topology(&slab).euler_characteristic, 0);
        let v = signed_volume(&slab);
        assert!(
            (v / (whole / 2.0) - 1.0).abs() < 2e-3,
            "{v} vs {}",
            whole / 2.0
        );
    }

    fn check_closed_no_normals(mesh: &TriMesh) {
        let t = topology(mesh);
        assert!(t.is_closed_manifold(), "{t:?}");
        assert_eq!(t.degenerate_triangles, 0);
        assert!(mesh.normals.is_empty());
    }
}
