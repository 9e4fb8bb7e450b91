//! Self-intersections: the faces of a mesh that cross, touch or overlap another face of the
//! same mesh, decided exactly. The narrow phase follows the segment–triangle formulation of
//! Möller 1997 (*A fast triangle–triangle intersection test*) and Guigue & Devillers 2003
//! (*Fast and robust triangle–triangle overlap test using orientation predicates*), with every
//! decision a sign of Shewchuk's adaptive exact `orient3d` and `orient2d` (the `robust` crate)
//! on the vertices widened to `f64`, so no tolerance is involved: two closed triangles meet
//! when some edge of one meets the other (on a common line the meeting segment ends on an
//! edge), and an edge meets a triangle when its ends are not strictly on one side of the
//! triangle's plane and the line through it passes the triangle's three edges on no two
//! opposite sides; coplanar cases are settled in the axis plane where the triangle has area.
//!
//! Faces that share corners (the same vertex, or vertices at the same place, as Marching Cubes
//! makes where the surface passes through a grid vertex) intersect only where they have more
//! in common than those corners: sharing a vertex, where the edge opposite it in one face meets
//! the other face (a ray from the vertex leaves both faces through their opposite edges, and
//! the nearer exit lies in the other face); sharing an edge, where the two faces are coplanar
//! and lie on the same side of it (folded over). Degenerate faces (a repeated vertex, or three
//! collinear corners) enclose nothing and are skipped: on a closed mesh the neighbour across a
//! collinear face's longest edge covers it.
//!
//! Broad phase: a uniform grid over the faces' bounding boxes, as entries `cell << 32 | face`
//! for every cell a box overlaps, sorted; a pair is tested only in the lowest cell of its boxes'
//! overlap, so once. The result is a set of faces, the same for any thread count and order.

mod predicates;

use std::sync::atomic::{AtomicBool, Ordering};

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::adjacency::VertexFaces;
use predicates::{faces_meet, orient2};

/// Faces per parallel task of the per-face passes.
const CHUNK: usize = 1 << 12;
/// Grid entries per parallel task of the pair tests (cut at cell boundaries).
const ENTRY_CHUNK: usize = 1 << 14;
/// The grid's cells are this many mean face extents wide (measured on cbd-small and cbd-large
/// at r/2: see `Grid::new`).
const CELL_EXTENTS: f64 = 2.0;
/// At most this many grid entries per face: a few faces far larger than the rest widen the
/// grid's cells instead of filling thousands of cells each.
const MAX_ENTRIES_PER_FACE: usize = 4;

/// The faces of `triangles` (indices into `vertices`) that intersect another face beyond their
/// shared corners (see the module's header), in increasing order. The same for any number of
/// threads. Faces with a repeated vertex or collinear corners are never listed. Vertices must
/// be finite.
pub fn self_intersecting_faces(vertices: &[Vec3], triangles: &[[u32; 3]]) -> Vec<u32> {
    let turns: Vec<Turns> = triangles
        .par_iter()
        .with_min_len(CHUNK)
        .map(|t| Turns::of(vertices, t))
        .collect();
    let flat = flat_stars(vertices, triangles, &turns);
    let bounds = |f: usize| turns[f].area().then(|| Aabb::of(vertices, &triangles[f]));
    let grid = Grid::new(triangles.len(), &bounds);
    let flags = Flags::new(triangles.len());
    if let Some(grid) = &grid {
        grid.all_pairs(
            &|f: usize| {
                let t = triangles[f];
                (Aabb::of(vertices, &t), t, t.map(|v| flat[v as usize]))
            },
            |f, g| {
                faces_meet(
                    corners(vertices, &triangles[f as usize]),
                    corners(vertices, &triangles[g as usize]),
                )
            },
            &flags,
        );
    }
    flags.listed()
}

/// How a face turns seen along each axis: the exact signs of its cross product's components
/// (the orientations of its three axis projections), two bits an axis (01 counter-clockwise,
/// 10 clockwise, 00 edge-on); [`Turns::REPEATS`] for a face that repeats a vertex.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Turns(u8);

impl Turns {
    const REPEATS: Turns = Turns(u8::MAX);

    fn of(vertices: &[Vec3], t: &[u32; 3]) -> Turns {
        if repeats(t) {
            return Turns::REPEATS;
        }
        let p = corners(vertices, t);
        Turns((0..3).fold(0, |bits, k| {
            bits | match orient2(p[0], p[1], p[2], k) {
                1 => 1,
                -1 => 2,
                _ => 0,
            } << (2 * k)
        }))
    }

    /// Whether the face has area: no repeated vertex, corners not collinear.
    fn area(self) -> bool {
        self != Turns::REPEATS && self.0 != 0
    }

    /// The sign of the orientation seen along `axis`.
    fn along(self, axis: usize) -> i8 {
        match self.0 >> (2 * axis) & 3 {
            1 => 1,
            2 => -1,
            _ => 0,
        }
    }
}

/// Which vertices have a flat star: their faces form one closed fan that some axis projection
/// lays out one to one, each face turning the same way and the fan going round once. Two faces
/// of such a star then meet only in their common vertex or edge, so most of the pairs that
/// share a vertex (three in four of the pairs whose boxes overlap, on a post-processed mesh)
/// need no test.
fn flat_stars(vertices: &[Vec3], triangles: &[[u32; 3]], turns: &[Turns]) -> Vec<bool> {
    let rows = VertexFaces::new(vertices.len(), triangles);
    (0..vertices.len())
        .into_par_iter()
        .with_min_len(CHUNK)
        .map(|v| flat_star(vertices, triangles, turns, rows.row(v), v as u32))
        .collect()
}

/// Whether the faces at `corners` (the corners `3 f + k` of vertex `v`) form a flat star (see
/// [`flat_stars`]).
fn flat_star(
    vertices: &[Vec3],
    triangles: &[[u32; 3]],
    turns: &[Turns],
    corners: &[u32],
    v: u32,
) -> bool {
    const MOST: usize = 32;
    let k = corners.len();
    if !(3..=MOST).contains(&k) {
        return false;
    }
    // The corners after `v` in each face, in its winding order, and the face.
    let mut fan = [(0u32, 0u32, Turns(0)); MOST];
    for (slot, &c) in fan.iter_mut().zip(corners) {
        let (f, i) = ((c / 3) as usize, (c % 3) as usize);
        let t = &triangles[f];
        if !turns[f].area() {
            return false;
        }
        *slot = (t[(i + 1) % 3], t[(i + 2) % 3], turns[f]);
    }
    let fan = &fan[..k];
    // One closed fan: from each face exactly one face goes on (its first corner being this
    // one's second), and the walk comes back to the first face after visiting all.
    let mut at = 0;
    for step in 1..=k {
        let mut next = (0..k).filter(|&j| fan[j].0 == fan[at].1);
        match (next.next(), next.next()) {
            (Some(j), None) => at = j,
            _ => return false,
        }
        if at == 0 {
            if step != k {
                return false;
            }
            break;
        }
    }
    if at != 0 {
        return false;
    }
    let o = vertices[v as usize];
    (0..3).any(|axis| {
        let turn = fan[0].2.along(axis);
        if turn == 0 || fan.iter().any(|e| e.2.along(axis) != turn) {
            return false;
        }
        // Every face turns the same way seen along the axis; the half-open wedges [a, b) they
        // span around `v` (counter-clockwise) hold the projection's first direction exactly
        // once: the fan goes round once.
        let w = (axis + 2) % 3;
        let rounds = fan
            .iter()
            .filter(|&&(a, b, _)| {
                let (a, b) = if turn > 0 { (a, b) } else { (b, a) };
                let (a, b) = (vertices[a as usize][w], vertices[b as usize][w]);
                a <= o[w] && o[w] < b
            })
            .count();
        rounds == 1
    })
}

/// One flag per face, set from any thread.
struct Flags(Vec<AtomicBool>);

impl Flags {
    fn new(faces: usize) -> Flags {
        Flags((0..faces).map(|_| AtomicBool::new(false)).collect())
    }

    fn set(&self, f: u32, g: u32) {
        self.0[f as usize].store(true, Ordering::Relaxed);
        self.0[g as usize].store(true, Ordering::Relaxed);
    }

    /// Whether both faces are already known to intersect something: their pair cannot add to
    /// the set.
    fn both(&self, f: u32, g: u32) -> bool {
        self.0[f as usize].load(Ordering::Relaxed) && self.0[g as usize].load(Ordering::Relaxed)
    }

    fn listed(self) -> Vec<u32> {
        let flags = self.0;
        (0..flags.len() as u32)
            .into_par_iter()
            .with_min_len(CHUNK)
            .filter(|&f| flags[f as usize].load(Ordering::Relaxed))
            .collect()
    }
}

/// An axis-aligned box, closed.
#[derive(Debug, Clone, Copy)]
struct Aabb {
    min: Vec3,
    max: Vec3,
}

impl Aabb {
    fn of(vertices: &[Vec3], t: &[u32; 3]) -> Aabb {
        let [a, b, c] = t.map(|i| vertices[i as usize]);
        Aabb {
            min: a.min(b).min(c),
            max: a.max(b).max(c),
        }
    }

    fn union(self, other: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }
}

/// A face as the broad phase sees it: its box, its vertices and which of them have a flat
/// star (see [`flat_stars`]).
type Entered = (Aabb, [u32; 3], [bool; 3]);

/// The faces of one cell, their boxes as columns (so that one face's box is compared with the
/// others' in a loop without branches), their vertices and the cells of their minima.
#[derive(Default)]
struct Run {
    faces: Vec<u32>,
    vertices: Vec<[u32; 3]>,
    flat: Vec<[bool; 3]>,
    cells: Vec<[u32; 3]>,
    min: [Vec<f32>; 3],
    max: [Vec<f32>; 3],
}

impl Run {
    fn fill(&mut self, grid: &Grid, entries: &[u64], face: &(impl Fn(usize) -> Entered + Sync)) {
        self.faces.clear();
        self.vertices.clear();
        self.flat.clear();
        self.cells.clear();
        self.min
            .iter_mut()
            .chain(&mut self.max)
            .for_each(Vec::clear);
        for &e in entries {
            let f = e as u32;
            let (b, t, flat) = face(f as usize);
            self.faces.push(f);
            self.vertices.push(t);
            self.flat.push(flat);
            self.cells.push(grid.cell(b.min));
            for k in 0..3 {
                self.min[k].push(b.min[k]);
                self.max[k].push(b.max[k]);
            }
        }
    }

    /// `visit(f, g)` for each pair of faces whose boxes overlap and whose overlap's lowest cell
    /// (that of the larger minimum, which [`Grid::cell`] is monotone in) is `here`, but for
    /// those that share a vertex with a flat star.
    fn pairs(&self, here: [u32; 3], mut visit: impl FnMut(u32, u32)) {
        let n = self.faces.len();
        for i in 0..n {
            let (lo, hi) = (
                self.min.each_ref().map(|c| c[i]),
                self.max.each_ref().map(|c| c[i]),
            );
            let mut j = i + 1;
            while j < n {
                let len = (n - j).min(64);
                let [x0, y0, z0] = self.min.each_ref().map(|c| &c[j..j + len]);
                let [x1, y1, z1] = self.max.each_ref().map(|c| &c[j..j + len]);
                let mut mask = 0u64;
                for t in 0..x0
                    .len()
                    .min(y0.len())
                    .min(z0.len())
                    .min(x1.len())
                    .min(y1.len())
                    .min(z1.len())
                {
                    let overlap = (x0[t] <= hi[0])
                        & (lo[0] <= x1[t])
                        & (y0[t] <= hi[1])
                        & (lo[1] <= y1[t])
                        & (z0[t] <= hi[2])
                        & (lo[2] <= z1[t]);
                    mask |= u64::from(overlap) << t;
                }
                while mask != 0 {
                    let k = j + mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    let (a, b) = (self.cells[i], self.cells[k]);
                    let (p, q) = (&self.vertices[i], &self.vertices[k]);
                    if (0..3).all(|c| a[c].max(b[c]) == here[c])
                        && !(0..3).any(|c| self.flat[i][c] && q.contains(&p[c]))
                    {
                        visit(self.faces[i], self.faces[k]);
                    }
                }
                j += len;
            }
        }
    }
}

/// The uniform grid of the broad phase: every face's entries `cell << 32 | face`, sorted.
struct Grid {
    origin: DVec3,
    /// 1 / the cell size.
    scale: f64,
    dims: [u32; 3],
    entries: Vec<u64>,
}

impl Grid {
    /// The grid over the boxes `bounds(f)` of faces `0..faces` (`None`: a face left out), or
    /// `None` when all are left out. Cells of [`CELL_EXTENTS`] mean box extents (the largest
    /// side) gave the fastest detection on cbd-small and cbd-large f23 at r/2, about two
    /// entries per face; widened until the grid has under 2^32 cells and at most
    /// [`MAX_ENTRIES_PER_FACE`] entries per face.
    fn new(faces: usize, bounds: &(impl Fn(usize) -> Option<Aabb> + Sync)) -> Option<Grid> {
        // Bounds and extents summed per chunk, then in order: the same grid on any thread count.
        let chunks: Vec<(Option<Aabb>, f64, usize)> = (0..faces.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let mut out = (None::<Aabb>, 0.0, 0);
                for f in c * CHUNK..((c + 1) * CHUNK).min(faces) {
                    if let Some(b) = bounds(f) {
                        out.0 = Some(out.0.map_or(b, |u| u.union(b)));
                        out.1 += f64::from((b.max - b.min).max_element());
                        out.2 += 1;
                    }
                }
                out
            })
            .collect();
        let (mut all, mut extents, mut count) = (None::<Aabb>, 0.0, 0);
        for (b, e, n) in chunks {
            if let Some(b) = b {
                all = Some(all.map_or(b, |u| u.union(b)));
            }
            extents += e;
            count += n;
        }
        let all = all?;
        let span = (all.max - all.min).as_dvec3();
        // A mesh of points (every box flat to nothing) still needs a positive cell.
        let mut size = (CELL_EXTENTS * extents / count as f64)
            .max(span.max_element() * 1e-6)
            .max(f64::MIN_POSITIVE);
        loop {
            let mut grid = Grid {
                origin: all.min.as_dvec3(),
                scale: 1.0 / size,
                dims: [0; 3],
                entries: Vec::new(),
            };
            let dims = (span * grid.scale).floor() + 1.0;
            if dims.x * dims.y * dims.z < u32::MAX as f64 {
                grid.dims = dims.to_array().map(|d| d as u32);
                if grid.fill(faces, bounds, count * MAX_ENTRIES_PER_FACE) {
                    return Some(grid);
                }
            }
            size *= 2.0;
        }
    }

    /// Fills and sorts the entries; false (nothing filled) when there would be more than
    /// `limit`.
    fn fill(
        &mut self,
        faces: usize,
        bounds: &(impl Fn(usize) -> Option<Aabb> + Sync),
        limit: usize,
    ) -> bool {
        let cells = |f: usize| {
            bounds(f).map_or(0, |b| {
                let (lo, hi) = (self.cell(b.min), self.cell(b.max));
                (0..3)
                    .map(|k| (hi[k] - lo[k] + 1) as usize)
                    .product::<usize>()
            })
        };
        let counts: Vec<usize> = (0..faces.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| (c * CHUNK..((c + 1) * CHUNK).min(faces)).map(cells).sum())
            .collect();
        let total: usize = counts.iter().sum();
        if total > limit {
            return false;
        }
        let mut entries = vec![0u64; total];
        // Each chunk of faces writes its own run of entries.
        let mut rest = entries.as_mut_slice();
        let mut runs = Vec::with_capacity(counts.len());
        for (c, &n) in counts.iter().enumerate() {
            let (run, tail) = std::mem::take(&mut rest).split_at_mut(n);
            runs.push((c, run));
            rest = tail;
        }
        runs.into_par_iter().for_each(|(c, run)| {
            let mut slots = run.iter_mut();
            for f in c * CHUNK..((c + 1) * CHUNK).min(faces) {
                let Some(b) = bounds(f) else { continue };
                let (lo, hi) = (self.cell(b.min), self.cell(b.max));
                for z in lo[2]..=hi[2] {
                    for y in lo[1]..=hi[1] {
                        for x in lo[0]..=hi[0] {
                            *slots.next().expect("counted") =
                                u64::from(self.index([x, y, z])) << 32 | f as u64;
                        }
                    }
                }
            }
        });
        // Filled in face order: sorted stably by cell alone (half the passes of the whole
        // word), each cell lists its faces in order, as a sort of the whole word would.
        radsort::sort_by_key(&mut entries, |e| (e >> 32) as u32);
        self.entries = entries;
        true
    }

    /// The cell holding `p`, clamped to the grid (monotone in each coordinate, so a box's
    /// cells are those from its minimum's to its maximum's).
    fn cell(&self, p: Vec3) -> [u32; 3] {
        let c = (p.as_dvec3() - self.origin) * self.scale;
        // Truncation is the floor here, at a fraction of its cost (a libm call without SSE4.1).
        std::array::from_fn(|k| (c[k].max(0.0) as u32).min(self.dims[k] - 1))
    }

    fn index(&self, [x, y, z]: [u32; 3]) -> u32 {
        x + self.dims[0] * (y + self.dims[1] * z)
    }

    /// `meet(f, g)` for every pair of entered faces whose boxes overlap, once each (in the
    /// lowest cell of the overlap), unless they share a vertex with a flat star or both are
    /// flagged already; flags both faces of each pair that meets.
    fn all_pairs(
        &self,
        face: &(impl Fn(usize) -> Entered + Sync),
        meet: impl Fn(u32, u32) -> bool + Sync,
        flags: &Flags,
    ) {
        let entries = &self.entries;
        // Task boundaries moved forward to the next cell's start.
        let cell_start = |i: usize| {
            let mut i = i.min(entries.len());
            while i > 0 && i < entries.len() && entries[i] >> 32 == entries[i - 1] >> 32 {
                i += 1;
            }
            i
        };
        let starts: Vec<usize> = (0..entries.len().div_ceil(ENTRY_CHUNK))
            .map(|c| cell_start(c * ENTRY_CHUNK))
            .chain([entries.len()])
            .collect();
        starts.par_windows(2).for_each_init(Run::default, |run, w| {
            let mut i = w[0];
            while i < w[1] {
                let cell = (entries[i] >> 32) as u32;
                let end = i + entries[i..w[1]].partition_point(|&e| e >> 32 == u64::from(cell));
                run.fill(self, &entries[i..end], face);
                run.pairs(self.coordinates(cell), |f, g| {
                    if !flags.both(f, g) && meet(f, g) {
                        flags.set(f, g);
                    }
                });
                i = end;
            }
        });
    }

    /// The cell of index `cell`.
    fn coordinates(&self, cell: u32) -> [u32; 3] {
        let [nx, ny, _] = self.dims;
        [cell % nx, cell / nx % ny, cell / nx / ny]
    }
}

fn corners(vertices: &[Vec3], t: &[u32; 3]) -> [DVec3; 3] {
    t.map(|i| vertices[i as usize].as_dvec3())
}

fn repeats(t: &[u32; 3]) -> bool {
    t[0] == t[1] || t[1] == t[2] || t[0] == t[2]
}

#[cfg(test)]
mod tests;
