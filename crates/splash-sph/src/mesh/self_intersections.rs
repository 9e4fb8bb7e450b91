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

use std::sync::atomic::{AtomicBool, Ordering};

use glam::{DVec3, Vec3};
use rayon::prelude::*;
use robust::{Coord, Coord3D, orient2d, orient3d};

use super::adjacency::VertexFaces;

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
fn orient2(a: DVec3, b: DVec3, c: DVec3, k: usize) -> i8 {
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
fn faces_meet(p: [DVec3; 3], q: [DVec3; 3]) -> bool {
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

#[cfg(test)]
pub(crate) mod tests {
    use std::f32::consts::{PI, TAU};

    use super::*;
    use crate::data::TriMesh;
    use crate::tests::common::{merged, torus, uniform};

    /// A closed UV sphere, outward: `rings` bands of `segments` quads split in two, fans at the
    /// poles (vertex 0 the north pole, the last the south pole).
    pub(crate) fn sphere(centre: Vec3, radius: f32, rings: u32, segments: u32) -> TriMesh {
        let mut vertices = vec![centre + radius * Vec3::Z];
        for i in 1..rings {
            let theta = PI * i as f32 / rings as f32;
            for j in 0..segments {
                let phi = TAU * j as f32 / segments as f32;
                let d = Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    theta.cos(),
                );
                vertices.push(centre + radius * d);
            }
        }
        vertices.push(centre - radius * Vec3::Z);
        let south = vertices.len() as u32 - 1;
        let at = |i: u32, j: u32| 1 + (i - 1) * segments + j % segments;
        let mut triangles = Vec::new();
        for j in 0..segments {
            triangles.push([0, at(1, j), at(1, j + 1)]);
            for i in 1..rings - 1 {
                let (u, u1, l, l1) = (at(i, j), at(i, j + 1), at(i + 1, j), at(i + 1, j + 1));
                triangles.extend([[u, l, l1], [u, l1, u1]]);
            }
            triangles.push([south, at(rings - 1, j + 1), at(rings - 1, j)]);
        }
        TriMesh {
            vertices,
            normals: Vec::new(),
            triangles,
        }
    }

    fn found(m: &TriMesh) -> Vec<u32> {
        self_intersecting_faces(&m.vertices, &m.triangles)
    }

    fn soup(triangles: &[[f32; 9]]) -> TriMesh {
        TriMesh {
            vertices: triangles
                .iter()
                .flat_map(|t| t.chunks(3).map(Vec3::from_slice))
                .collect(),
            normals: Vec::new(),
            triangles: (0..triangles.len() as u32)
                .map(|f| [3 * f, 3 * f + 1, 3 * f + 2])
                .collect(),
        }
    }

    #[test]
    fn a_closed_sphere_and_a_torus_do_not_cross_themselves() {
        assert!(found(&sphere(Vec3::ZERO, 1.0, 24, 48)).is_empty());
        assert!(found(&torus(48, 24, 1.0, 0.3, 0.5)).is_empty());
        // Apart in one mesh, nothing either.
        let two = merged(
            &sphere(Vec3::ZERO, 1.0, 16, 32),
            &sphere(Vec3::new(2.01, 0.0, 0.0), 1.0, 16, 32),
        );
        assert!(found(&two).is_empty());
    }

    #[test]
    fn two_overlapping_spheres_in_one_mesh_are_found_where_they_cross() {
        let (a, b) = (
            sphere(Vec3::ZERO, 1.0, 16, 32),
            sphere(Vec3::new(1.2, 0.0, 0.0), 1.0, 16, 32),
        );
        let two = merged(&a, &b);
        let crossing = found(&two);
        let first = a.triangles.len() as u32;
        assert!(crossing.iter().any(|&f| f < first) && crossing.iter().any(|&f| f >= first));
        // The spheres cross on the circle x = 0.6, radius 0.8: every face found reaches it.
        for &f in &crossing {
            let t = two.triangles[f as usize].map(|v| two.vertices[v as usize]);
            let (lo, hi) = (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]));
            assert!(lo.x <= 0.6 && 0.6 <= hi.x, "face {f}: {t:?}");
        }
    }

    #[test]
    fn a_vertex_pushed_through_the_opposite_side_is_found() {
        let mut ball = sphere(Vec3::ZERO, 1.0, 12, 24);
        ball.vertices[0] = Vec3::new(0.0, 0.0, -1.3);
        let crossing = found(&ball);
        // The north pole's fan, now a spike through the south cap, and the faces it pierces.
        let fan: Vec<u32> = (0..ball.triangles.len() as u32)
            .filter(|&f| ball.triangles[f as usize].contains(&0))
            .collect();
        assert!(fan.iter().all(|f| crossing.contains(f)), "{crossing:?}");
        assert!(crossing.len() > fan.len());
    }

    #[test]
    fn faces_that_touch_without_crossing_are_not_found() {
        let cases: [(&str, [[f32; 9]; 2]); 5] = [
            // Two faces of one plane meeting at a corner only (a bowtie), given as separate
            // vertices at the same place.
            (
                "bowtie",
                [
                    [0.0, 0.0, 0.0, 1.0, -0.5, 0.0, 1.0, 0.5, 0.0],
                    [0.0, 0.0, 0.0, -1.0, 0.5, 0.0, -1.0, -0.5, 0.0],
                ],
            ),
            // Two faces at a corner, one leaning over the other without reaching it.
            (
                "leaning",
                [
                    [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
                    [0.0, 0.0, 0.0, 1.0, 1.0, 1e-6, -1.0, 1.0, 1.0],
                ],
            ),
            // An edge shared by two faces folded almost flat onto each other, but not quite.
            (
                "nearly folded",
                [
                    [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.5, 1.0, 0.0],
                    [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5, 1.0, 1e-7],
                ],
            ),
            // A face one f32 step above another's corner, the rest far.
            (
                "one step apart",
                [
                    [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
                    [
                        0.25,
                        0.25,
                        f32::from_bits(1),
                        2.0,
                        0.25,
                        1.0,
                        0.25,
                        2.0,
                        1.0,
                    ],
                ],
            ),
            // Coplanar neighbours across an edge (a flat pair).
            (
                "flat pair",
                [
                    [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
                    [1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0],
                ],
            ),
        ];
        for (name, faces) in cases {
            assert!(found(&soup(&faces)).is_empty(), "{name}");
        }
    }

    #[test]
    fn faces_that_touch_beyond_their_shared_corners_are_found() {
        let cases: [(&str, [[f32; 9]; 2]); 4] = [
            // A corner of one face exactly on the inside of another.
            (
                "corner on a face",
                [
                    [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
                    [0.25, 0.25, 0.0, 2.0, 0.25, 1.0, 0.25, 2.0, 1.0],
                ],
            ),
            // A shared edge folded over: coplanar, both faces on the same side.
            (
                "folded edge",
                [
                    [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.5, 1.0, 0.0],
                    [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.3, 0.5, 0.0],
                ],
            ),
            // A shared corner, the faces coplanar and overlapping along a ray from it.
            (
                "corner and a ray",
                [
                    [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
                    [0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, -1.0, 0.0],
                ],
            ),
            // A shared corner, one face piercing the other.
            (
                "corner and a spike",
                [
                    [0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 2.0, 0.0],
                    [0.0, 0.0, 0.0, 0.5, 0.5, 1.0, 0.5, 0.5, -1.0],
                ],
            ),
        ];
        for (name, faces) in cases {
            assert_eq!(found(&soup(&faces)), [0, 1], "{name}");
        }
        // The same with shared vertex indices rather than equal positions.
        let folded = TriMesh {
            vertices: vec![
                Vec3::ZERO,
                Vec3::X,
                Vec3::new(0.5, 1.0, 0.0),
                Vec3::new(0.3, 0.5, 0.0),
            ],
            normals: Vec::new(),
            triangles: vec![[0, 1, 2], [1, 0, 3]],
        };
        assert_eq!(found(&folded), [0, 1]);
    }

    #[test]
    fn adjacent_faces_of_a_flat_grid_do_not_cross_and_degenerate_faces_are_skipped() {
        let n = 20u32;
        let mut grid = TriMesh::default();
        for y in 0..=n {
            for x in 0..=n {
                grid.vertices.push(Vec3::new(x as f32, y as f32, 0.0) * 0.1);
            }
        }
        let at = |x: u32, y: u32| y * (n + 1) + x;
        for y in 0..n {
            for x in 0..n {
                let (a, b, c, d) = (at(x, y), at(x + 1, y), at(x + 1, y + 1), at(x, y + 1));
                grid.triangles.extend([[a, b, c], [a, c, d]]);
            }
        }
        assert!(found(&grid).is_empty());
        // A face repeating a vertex and a collinear one, lying on the grid's faces.
        grid.triangles.push([0, 1, 1]);
        grid.triangles.push([at(0, 0), at(1, 1), at(2, 2)]);
        assert!(found(&grid).is_empty());
    }

    /// A noisy double sphere: many crossings, through flat and non-flat stars.
    fn tangled() -> TriMesh {
        let mut two = merged(
            &sphere(Vec3::ZERO, 1.0, 32, 64),
            &sphere(Vec3::new(0.9, 0.3, 0.0), 0.8, 32, 64),
        );
        let mut next = uniform(7);
        for p in &mut two.vertices {
            *p += 0.03 * (Vec3::new(next(), next(), next()) - 0.5);
        }
        two
    }

    #[test]
    fn the_faces_found_do_not_depend_on_the_thread_count() {
        let two = tangled();
        let pool = |n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .unwrap()
        };
        let one = pool(1).install(|| found(&two));
        assert!(one.len() > 100, "{}", one.len());
        assert_eq!(one, pool(2).install(|| found(&two)));
        assert_eq!(one, pool(3).install(|| found(&two)));
    }

    #[test]
    fn the_grid_finds_what_testing_every_pair_finds() {
        // Small faces scattered in a box, a few large ones across it, and pairs sharing
        // vertices, in one soup; every pair tested directly for reference.
        let mut next = uniform(11);
        let mut mesh = tangled();
        mesh.triangles.truncate(400);
        for k in 0..300 {
            let size = if k % 50 == 0 { 1.5 } else { 0.08 };
            let o = Vec3::new(next(), next(), next()) * 1.5 - 0.75;
            let base = mesh.vertices.len() as u32;
            for _ in 0..3 {
                mesh.vertices
                    .push(o + size * (Vec3::new(next(), next(), next()) - 0.5));
            }
            let shared = if k % 7 == 0 { 5 * k } else { base };
            mesh.triangles.push([shared, base + 1, base + 2]);
        }
        let faces = |f: usize| {
            let t = &mesh.triangles[f];
            Turns::of(&mesh.vertices, t)
                .area()
                .then(|| corners(&mesh.vertices, t))
        };
        let mut expected = vec![false; mesh.triangles.len()];
        for f in 0..mesh.triangles.len() {
            for g in f + 1..mesh.triangles.len() {
                if let (Some(p), Some(q)) = (faces(f), faces(g))
                    && faces_meet(p, q)
                {
                    expected[f] = true;
                    expected[g] = true;
                }
            }
        }
        let expected: Vec<u32> = (0..expected.len() as u32)
            .filter(|&f| expected[f as usize])
            .collect();
        assert!(expected.len() > 50, "{}", expected.len());
        assert_eq!(found(&mesh), expected);
    }
}
