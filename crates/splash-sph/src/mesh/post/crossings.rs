//! Faces that moving the vertices made cross (the smoothing and the volume steps where two
//! sheets are close; following the fluid towards the neighbours' surfaces): their corners, and
//! a ring around them, go back to where they were before (`before`), until nothing crosses
//! that did not before. Faces are tested exactly ([`self_intersecting_faces`]): the whole mesh
//! or the faces the caller names once, then only the faces near those put back, as no other
//! pair changed.

use glam::{IVec3, Vec3};
use rayon::prelude::*;
use rustc_hash::FxHashMap;

use crate::mesh::{area_normal, cells_between, self_intersecting_faces};
use crate::neighbours::cell_of;

/// Rounds of putting back: each looks again only near the faces whose corners went back.
const ROUNDS: usize = 3;

/// Puts back the `movable` vertices (those that moved since `before`) whose faces
/// cross another face, and a ring around them, to `before`, up to ROUNDS times: a mesh that
/// did not cross at `before` does not after. The first round tests the faces of `first` among
/// themselves (every face when None). Returns which vertices went back. What still crosses
/// crossed at `before` too.
fn put_back_crossings(
    vertices: &mut [Vec3],
    triangles: &[[u32; 3]],
    before: &[Vec3],
    movable: &[bool],
    first: Option<Vec<u32>>,
) -> Vec<bool> {
    let mut went_back = vec![false; vertices.len()];
    let mut near = first;
    for _ in 0..ROUNDS {
        let crossing = match &near {
            None => self_intersecting_faces(vertices, triangles),
            Some(faces) => {
                let some: Vec<[u32; 3]> = faces.iter().map(|&f| triangles[f as usize]).collect();
                self_intersecting_faces(vertices, &some)
                    .into_iter()
                    .map(|k| faces[k as usize])
                    .collect()
            }
        };
        if crossing.is_empty() {
            // Nothing crosses (the usual case): no ring to look for over the whole mesh.
            break;
        }
        let mut back = vec![false; vertices.len()];
        for &f in &crossing {
            for v in triangles[f as usize] {
                back[v as usize] = true;
            }
        }
        // One ring wider: every face touching a vertex going back takes its others along.
        let ring: Vec<u32> = triangles
            .iter()
            .filter(|t| t.iter().any(|&v| back[v as usize]))
            .flatten()
            .copied()
            .collect();
        let mut moved = vec![false; vertices.len()];
        let mut any = false;
        for v in ring {
            let v = v as usize;
            if movable[v] && !went_back[v] {
                vertices[v] = before[v];
                moved[v] = true;
                went_back[v] = true;
                any = true;
            }
        }
        if !any {
            // Nothing left to put back: what still crosses crossed before.
            break;
        }
        near = Some(faces_near(vertices, triangles, &moved));
    }
    went_back
}

/// Puts the faces that the smoothing and the volume steps made cross (where two sheets came
/// close: 19 faces of cbd-large f23 with its spacing estimated, 10 of the bundled frame at 2r;
/// none of the raw isosurface's) back towards their `raw` places with a ring around them (see
/// [`put_back_near`]). A midpoint of the refinement (`parents`: one end of each new vertex's
/// edge) goes back as far as its edge's end.
pub(super) fn uncross(
    vertices: &mut [Vec3],
    triangles: &[[u32; 3]],
    mut raw: Vec<Vec3>,
    parents: &[u32],
    close: &[bool],
) {
    raw.reserve_exact(parents.len());
    for (k, &p) in parents.iter().enumerate() {
        let (m, p) = (raw.len(), p as usize);
        debug_assert!(p < m && m == vertices.len() - parents.len() + k);
        raw.push(vertices[m] - (vertices[p] - raw[p]));
    }
    put_back_near(vertices, triangles, &raw, Some(close));
}

/// [`put_back_crossings`] for vertices that moved since `before`, testing at first only the
/// faces with a `close` corner, where another side of the surface faces it within the
/// clearance's reach, and the faces near a face turned over against its normal at `before` (a
/// fold); every face without `close`. After the post-processing: on the 36 meshes of
/// `scripts/same-meshes` (with 6 and 3 smoothing pairs first) and 112 frames of four sequences
/// the same result as testing every face, at a fifth of the time (cbd-large f23: 134 k of
/// 1.05 M faces, 33 ms against 187 ms); the close faces alone missed the folds of cbd-large f23
/// at cell r (14 crossing faces) once the relaxation ran before the smoothing. Returns which
/// vertices went back.
pub(crate) fn put_back_near(
    vertices: &mut [Vec3],
    triangles: &[[u32; 3]],
    before: &[Vec3],
    close: Option<&[bool]>,
) -> Vec<bool> {
    let movable: Vec<bool> = vertices
        .par_iter()
        .zip(before)
        .map(|(v, b)| v != b)
        .collect();
    let first = close.map(|close| first_faces(vertices, triangles, before, close));
    put_back_crossings(vertices, triangles, before, &movable, first)
}

/// The faces [`put_back_near`] tests first: those with a `close` corner and those near a face
/// turned over since `before`.
fn first_faces(
    vertices: &[Vec3],
    triangles: &[[u32; 3]],
    before: &[Vec3],
    close: &[bool],
) -> Vec<u32> {
    // Faces turned over (a fold, where the relaxation and the smoothing pulled a rim's
    // triangles past each other) cross their neighbours without two sides facing: the faces
    // near them are tested too.
    let near = turned_over(vertices, triangles, before).map(|corners| {
        let mut near = vec![false; triangles.len()];
        for f in faces_near(vertices, triangles, &corners) {
            near[f as usize] = true;
        }
        near
    });
    let near = |f: usize| near.as_ref().is_some_and(|near| near[f]);
    triangles
        .par_iter()
        .enumerate()
        .filter(|&(f, t)| near(f) || t.iter().any(|&v| close[v as usize]))
        .map(|(f, _)| f as u32)
        .collect()
}

/// The corners of the faces whose normal points against their normal at `raw`, or None when
/// no face turned over.
fn turned_over(vertices: &[Vec3], triangles: &[[u32; 3]], raw: &[Vec3]) -> Option<Vec<bool>> {
    let turned: Vec<&[u32; 3]> = triangles
        .par_iter()
        .with_min_len(4096)
        .filter(|t| area_normal(t, raw).dot(area_normal(t, vertices)) < 0.0)
        .collect();
    if turned.is_empty() {
        return None;
    }
    let mut corners = vec![false; vertices.len()];
    for &v in turned.into_iter().flatten() {
        corners[v as usize] = true;
    }
    Some(corners)
}

/// The faces whose bounding boxes meet the box of a face with a corner in `moved`: the only
/// faces that can meet those faces.
fn faces_near(vertices: &[Vec3], triangles: &[[u32; 3]], moved: &[bool]) -> Vec<u32> {
    let bounds = |t: &[u32; 3]| {
        let [a, b, c] = t.map(|i| vertices[i as usize]);
        (a.min(b).min(c), a.max(b).max(c))
    };
    let boxes: Vec<(Vec3, Vec3)> = triangles
        .iter()
        .filter(|t| t.iter().any(|&v| moved[v as usize]))
        .map(bounds)
        .collect();
    // Cells as wide as the widest moved box: each of those boxes meets at most 8.
    let size = boxes
        .iter()
        .map(|(lo, hi)| (*hi - *lo).max_element())
        .fold(0.0f32, f32::max)
        .max(f32::MIN_POSITIVE);
    let cell_of = |p: Vec3| cell_of(p, size);
    let cells = |lo: Vec3, hi: Vec3| cells_between(cell_of(lo), cell_of(hi));
    let mut grid: FxHashMap<IVec3, Vec<u32>> = FxHashMap::default();
    for (k, &(lo, hi)) in boxes.iter().enumerate() {
        for c in cells(lo, hi) {
            grid.entry(c).or_default().push(k as u32);
        }
    }
    // The box around them all turns most faces away at once (26 → 7 ms on cbd-large f23).
    let (all_lo, all_hi) = boxes
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), &(lo, hi)| {
            (l.min(lo), h.max(hi))
        });
    let meets = |(lo, hi): (Vec3, Vec3)| {
        if !(lo.cmple(all_hi).all() && all_lo.cmple(hi).all()) {
            return false;
        }
        // A face far wider than the moved ones is kept rather than walked cell by cell.
        let span = cell_of(hi) - cell_of(lo);
        span.max_element() > 8
            || cells(lo, hi).any(|c| {
                grid.get(&c).is_some_and(|ks| {
                    ks.iter().any(|&k| {
                        let (l, h) = boxes[k as usize];
                        lo.cmple(h).all() && l.cmple(hi).all()
                    })
                })
            })
    };
    triangles
        .par_iter()
        .with_min_len(4096)
        .enumerate()
        .filter(|(_, t)| meets(bounds(t)))
        .map(|(f, _)| f as u32)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat n × n grid of unit squares, two triangles each, at z = 0.
    fn grid(n: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let vertices = (0..=n)
            .flat_map(|y| (0..=n).map(move |x| Vec3::new(x as f32, y as f32, 0.0)))
            .collect();
        let at = |x: u32, y: u32| y * (n + 1) + x;
        let triangles = (0..n)
            .flat_map(|y| (0..n).map(move |x| (x, y)))
            .flat_map(|(x, y)| {
                [
                    [at(x, y), at(x + 1, y), at(x + 1, y + 1)],
                    [at(x, y), at(x + 1, y + 1), at(x, y + 1)],
                ]
            })
            .collect();
        (vertices, triangles)
    }

    /// A vertex dragged past its neighbour turns its faces over, into the faces of a raised
    /// vertex beyond, where no two sides of the surface face each other (no `close` corner):
    /// uncross still finds the fold and puts it back.
    #[test]
    fn a_fold_without_facing_sides_goes_back() {
        let (raw, triangles) = grid(6);
        let mut vertices = raw.clone();
        let centre = 3 * 7 + 3;
        vertices[centre] += Vec3::new(1.6, 0.2, 0.2);
        vertices[centre + 2].z = 1.0;
        assert_eq!(self_intersecting_faces(&vertices, &triangles).len(), 8);
        uncross(
            &mut vertices,
            &triangles,
            raw.clone(),
            &[],
            &vec![false; raw.len()],
        );
        assert!(self_intersecting_faces(&vertices, &triangles).is_empty());
        assert_eq!(vertices[centre], raw[centre]);
    }
}
