//! Refinement where the surface bends: every edge whose two triangles meet at more than an angle
//! is bisected at a curved midpoint (the cubic Hermite midpoint of its end normals, as in the
//! PN triangles of Vlachos et al. 2001), with Rivara's longest-edge closure (1984) so that the
//! pieces stay well shaped; red-green patterns keep the mesh conforming, so it stays closed,
//! manifold and outward. Then Delaunay edge flips (Lawson 1977) around the new vertices, where
//! the surface is nearly flat across the edge, undo the caps that bisecting obtuse triangles
//! leaves. The faceting of rims and droplets halves where the mesh is refined; flat and gently
//! curved parts keep their triangles.

use glam::Vec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering};

use crate::mesh::adjacency::VertexFaces;
use crate::mesh::unit_normal;

/// Triangles per parallel task.
const CHUNK: usize = 4096;
/// No triangle across an edge (boundary or non-manifold edge: never split nor flipped).
const NONE: u32 = u32::MAX;

/// Across each edge `t[k] → t[k + 1]` of each triangle, the triangle `g` on the other side and
/// the corner `j` of its reverse edge, packed as `3·g + j` ([`NONE`] unless the edge has exactly
/// one triangle on each side, oriented oppositely). Row by row: the edges out of a vertex and
/// the edges into it are the next and previous corners of its own row's triangles, so each row
/// pairs its own corners, reading each triangle three times in all rather than once per corner
/// of every neighbour; a pair counts only where both ends find each other.
fn twins(triangles: &[[u32; 3]], rings: VertexFaces) -> Vec<[u32; 3]> {
    let indices = triangles.as_flattened();
    let (next, prev) = (
        |c: u32| c - c % 3 + (c + 1) % 3,
        |c: u32| c - c % 3 + (c + 2) % 3,
    );
    // Every corner lies in exactly one row, which alone writes it, through an atomic view of
    // the result: no second array to copy, and no fill (zeroed pages come from the system
    // untouched; the rows' tasks fault them in).
    const _: () = assert!(align_of::<AtomicU32>() == align_of::<u32>());
    let mut twin = vec![[0u32; 3]; triangles.len()];
    {
        let flat: &mut [u32] = twin.as_flattened_mut();
        // SAFETY: AtomicU32 has the size and bit validity of u32 and, as asserted, its
        // alignment; `flat` is borrowed exclusively, so only `found` reaches the memory.
        let found = unsafe { &*(flat as *mut [u32] as *const [AtomicU32]) };
        (0..rings.offsets.len() - 1)
            .into_par_iter()
            .with_min_len(CHUNK)
            .for_each(|v| {
                let row = rings.row(v);
                for &c in row {
                    // The edge v → u out of corner c meets u → v, ending at a corner of this row.
                    let u = indices[next(c) as usize];
                    let mut twin = NONE;
                    for &d in row {
                        if indices[prev(d) as usize] == u {
                            if twin != NONE {
                                twin = NONE;
                                break;
                            }
                            twin = prev(d);
                        }
                    }
                    found[c as usize].store(twin, Ordering::Relaxed);
                }
            });
    }
    drop(rings);
    let asymmetric: Vec<u32> = (0..3 * triangles.len() as u32)
        .into_par_iter()
        .with_min_len(3 * CHUNK)
        .filter(|&c| {
            let o = twin[(c / 3) as usize][(c % 3) as usize];
            o != NONE && twin[(o / 3) as usize][(o % 3) as usize] != c
        })
        .collect();
    for c in asymmetric {
        twin[(c / 3) as usize][(c % 3) as usize] = NONE;
    }
    twin
}

/// The id of the edge at corner `c = 3·f + k`: the smaller of its two corners.
#[inline]
fn edge_id(c: u32, twin: u32) -> u32 {
    if twin == NONE { NONE } else { c.min(twin) }
}

/// Bisects the edges of `triangles` whose dihedral angle exceeds `angle` (radians), and then
/// the longest edge of every triangle that has a bisected edge until none is left without it;
/// then flips the non-Delaunay edges around the new vertices. New vertices are appended to
/// `vertices` (and get the normalised mean of their ends' `normals`, which must be unit vertex
/// normals). `rings` must be those of `triangles` (dropped once read, to keep the peak memory
/// down). The result does not depend on the thread
/// count. Returns, for each new vertex in order, one end of the edge it bisects.
pub fn refine_bends(
    vertices: &mut Vec<Vec3>,
    normals: &mut Vec<Vec3>,
    triangles: &mut Vec<[u32; 3]>,
    rings: VertexFaces,
    angle: f32,
) -> Vec<u32> {
    let first = vertices.len() as u32;
    let (parents, twin) = bisect(vertices, normals, triangles, rings, angle);
    if !parents.is_empty() {
        flip_around(vertices, triangles, twin, first);
    }
    parents
}

/// [`refine_bends`] before the flips; also returns the twins of the refined triangles (empty
/// when nothing is bisected).
fn bisect(
    vertices: &mut Vec<Vec3>,
    normals: &mut Vec<Vec3>,
    triangles: &mut Vec<[u32; 3]>,
    rings: VertexFaces,
    angle: f32,
) -> (Vec<u32>, Vec<[u32; 3]>) {
    let twin = twins(triangles, rings);
    let ids =
        |f: usize| -> [u32; 3] { std::array::from_fn(|k| edge_id((3 * f + k) as u32, twin[f][k])) };
    // Unit face normals, each made once rather than once per edge that reads it.
    let unit: Vec<Vec3> = triangles
        .par_iter()
        .with_min_len(CHUNK)
        .map(|t| unit_normal(t, vertices))
        .collect();
    let cos_max = angle.cos();
    // Split flags by edge id (the owning corner); each triangle writes only its own corners.
    let mut split = vec![false; 3 * triangles.len()];
    split
        .par_chunks_mut(3)
        .with_min_len(CHUNK)
        .zip(&twin)
        .enumerate()
        .for_each(|(f, (flags, tw))| {
            for k in 0..3 {
                let c = (3 * f + k) as u32;
                if edge_id(c, tw[k]) == c {
                    flags[k] = unit[f].dot(unit[(tw[k] / 3) as usize]) < cos_max;
                }
            }
        });
    drop(unit);
    // Rivara's closure: a triangle with a bisected edge has its longest edge bisected too. The
    // split edges only grow, to the same smallest closed set in any order of work.
    let longest = |f: usize| longest_edge(vertices, &triangles[f], &ids(f));
    let mut work: Vec<u32> = (0..triangles.len() as u32)
        .into_par_iter()
        .with_min_len(CHUNK)
        .filter(|&f| {
            ids(f as usize)
                .iter()
                .any(|&e| e != NONE && split[e as usize])
        })
        .collect();
    if work.is_empty() {
        return (Vec::new(), Vec::new());
    }
    while let Some(f) = work.pop() {
        let f = f as usize;
        let l = longest(f);
        if l < 3 && !split[ids(f)[l] as usize] {
            split[ids(f)[l] as usize] = true;
            work.push(twin[f][l] / 3);
        }
    }

    // New vertices in edge-id order.
    let first = vertices.len() as u32;
    let bisected: Vec<u32> = (0..split.len() as u32)
        .filter(|&e| split[e as usize])
        .collect();
    let parents: Vec<u32> = bisected
        .iter()
        .map(|&e| triangles[(e / 3) as usize][(e % 3) as usize])
        .collect();
    let (mids, mid_normals): (Vec<Vec3>, Vec<Vec3>) = bisected
        .par_iter()
        .with_min_len(CHUNK)
        .map(|&e| {
            let (f, k) = ((e / 3) as usize, (e % 3) as usize);
            let (a, b) = (triangles[f][k] as usize, triangles[f][(k + 1) % 3] as usize);
            let (n, m) = (normals[a], normals[b]);
            (
                curved_midpoint(vertices[a], vertices[b], n, m),
                (n + m).normalize_or_zero(),
            )
        })
        .unzip();
    let midpoint = |e: u32| -> u32 {
        bisected
            .binary_search(&e)
            .map_or(NONE, |i| first + i as u32)
    };
    // Each triangle's layout (bisected edges and longest edge), and where its pieces start.
    let codes: Vec<u8> = (0..triangles.len())
        .into_par_iter()
        .with_min_len(CHUNK)
        .map(|f| {
            let mask = ids(f)
                .iter()
                .enumerate()
                .map(|(k, &e)| u8::from(e != NONE && split[e as usize]) << k)
                .sum::<u8>();
            let l = if mask == 0 { 0 } else { longest(f) as u8 };
            mask | l << 3
        })
        .collect();
    drop(split);
    let layouts = Layout::all();
    let mut start = Vec::with_capacity(triangles.len() + 1);
    start.push(0u32);
    for &code in &codes {
        start.push(start[start.len() - 1] + layouts[code as usize].count as u32);
    }
    // Each triangle's pieces at `start[f]..start[f + 1]` of a new array, in parallel over runs
    // of triangles. (Both arrays are held for a moment; the peak comes later, in the
    // relaxation of the refined mesh.)
    let total = start[triangles.len()] as usize;
    let mut pieces = vec![[0u32; 3]; total];
    fill_pieces(&mut pieces, &start, |f, out| {
        let t = triangles[f];
        let e = ids(f);
        let mids: [u32; 3] = std::array::from_fn(|k| {
            if codes[f] >> k & 1 == 1 {
                midpoint(e[k])
            } else {
                NONE
            }
        });
        let ends = [t[0], t[1], t[2], mids[0], mids[1], mids[2]];
        let layout = &layouts[codes[f] as usize];
        for (slots, piece) in layout.pieces[..layout.count].iter().zip(out) {
            *piece = slots.map(|s| ends[s as usize]);
        }
    });
    *triangles = pieces;
    drop(bisected);
    // The refined mesh's twins from the old ones the same way: a piece's edge on half `h` of
    // its parent's edge `k` meets the other half (or the whole edge) of the twin triangle's
    // edge.
    // Every slot is written below: zeroed pages, not a fill on one thread.
    let mut refined = vec![[0u32; 3]; total];
    fill_pieces(&mut refined, &start, |f, out| {
        let tw = twin[f];
        let layout = &layouts[codes[f] as usize];
        for (edges, piece) in layout.edges[..layout.count].iter().zip(out) {
            *piece = edges.map(|edge| match edge {
                Edge::Inner(p, i) => 3 * (start[f] + u32::from(p)) + u32::from(i),
                Edge::Side(k, h) => {
                    let o = tw[k as usize];
                    if o == NONE {
                        return NONE;
                    }
                    let (g, j) = ((o / 3) as usize, (o % 3) as usize);
                    let half = if codes[f] >> k & 1 == 1 { 1 - h } else { 0 };
                    3 * start[g] + u32::from(layouts[codes[g] as usize].sides[j][half as usize])
                }
            });
        }
    });
    drop(twin);
    let twin = refined;
    drop((codes, start));
    vertices.reserve_exact(mids.len());
    vertices.extend(mids);
    normals.reserve_exact(mid_normals.len());
    normals.extend(mid_normals);
    (parents, twin)
}

/// Fills `out`, the refined triangles (or their twins; `start` as in [`bisect`]), in parallel
/// over runs of [`CHUNK`] triangles: `fill(f, slots)` writes the pieces of triangle `f`.
fn fill_pieces<T: Send>(mut out: &mut [T], start: &[u32], fill: impl Fn(usize, &mut [T]) + Sync) {
    let old = start.len() - 1;
    let runs: Vec<(usize, &mut [T])> = (0..old)
        .step_by(CHUNK)
        .map(|first| {
            let end = (first + CHUNK).min(old);
            let len = (start[end] - start[first]) as usize;
            let (run, rest) = std::mem::take(&mut out).split_at_mut(len);
            out = rest;
            (first, run)
        })
        .collect();
    runs.into_par_iter().for_each(|(first, run)| {
        let base = start[first];
        for f in first..(first + CHUNK).min(old) {
            fill(
                f,
                &mut run[(start[f] - base) as usize..(start[f + 1] - base) as usize],
            );
        }
    });
}

/// The index (0 for `ab`, 1 for `bc`, 2 for `ca`) of the longest splittable edge of `t`, ties
/// to the smaller edge id; 3 when no edge can be split.
fn longest_edge(vertices: &[Vec3], t: &[u32; 3], ids: &[u32; 3]) -> usize {
    (0..3)
        .filter(|&k| ids[k] != NONE)
        .map(|k| {
            let (a, b) = (vertices[t[k] as usize], vertices[t[(k + 1) % 3] as usize]);
            (k, a.distance_squared(b))
        })
        .max_by(|x, y| x.1.total_cmp(&y.1).then_with(|| ids[y.0].cmp(&ids[x.0])))
        .map_or(3, |(k, _)| k)
}

/// The midpoint of the cubic Hermite curve from `p` to `q` whose tangents lie in the planes of
/// the unit normals `n` and `m`: the chord's midpoint bent by an eighth of the difference of
/// the chord's normal parts.
fn curved_midpoint(p: Vec3, q: Vec3, n: Vec3, m: Vec3) -> Vec3 {
    let d = q - p;
    0.5 * (p + q) + (d.dot(m) * m - d.dot(n) * n) / 8.0
}

/// What an edge of a piece lies on: half `h` of the parent triangle's edge `k` (`Side(k, h)`;
/// `h` 0 for the whole edge or its first half from corner `k`, 1 for its second half), or,
/// inside the parent, the edge at corner `i` of its piece `p` (`Inner(p, i)`), walked the other
/// way.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Edge {
    Side(u8, u8),
    Inner(u8, u8),
}

/// The pieces of a triangle `a b c`, in the triangle's own terms: `pieces` name its corners 0-2
/// and the midpoints 3-5 of its edges `ab`, `bc`, `ca`, keeping its winding; `edges` say what
/// each piece's edge (from its corner `i` to `i + 1`) lies on.
#[derive(Debug, Clone, Copy)]
struct Layout {
    count: usize,
    pieces: [[u8; 3]; 4],
    edges: [[Edge; 3]; 4],
    /// `3 p + i` for the piece `p` whose edge at corner `i` lies on half `h` of edge `k`, at
    /// `[k][h]`.
    sides: [[u8; 2]; 3],
}

impl Layout {
    /// The layout of a triangle whose bisected edges are the bits 0-2 of `code` and whose
    /// longest edge, bits 3-4, is one of them (Rivara's closure): with one or two bisected edges
    /// the longest is bisected first, as Rivara does; with three, red refinement.
    fn of(code: u8) -> Layout {
        use Edge::{Inner as I, Side as S};
        let (mask, l) = (code & 7, code >> 3);
        // Corner, midpoint and edge `i` of the triangle turned so that its longest edge is 0.
        let c = |i: u8| (i + l) % 3;
        let m = |i: u8| 3 + (i + l) % 3;
        let s = |e: u8, h: u8| S((e + l) % 3, h);
        let rotated_mask = (mask >> l | mask << (3 - l)) & 7;
        let none = [I(0, 0); 3];
        let (count, pieces, edges) = match (mask, rotated_mask) {
            (0, _) => (
                1,
                [[0, 1, 2]; 4],
                [[S(0, 0), S(1, 0), S(2, 0)], none, none, none],
            ),
            (7, _) => (
                4,
                [[0, 3, 5], [3, 1, 4], [5, 4, 2], [3, 4, 5]],
                [
                    [S(0, 0), I(3, 2), S(2, 1)],
                    [S(0, 1), S(1, 0), I(3, 0)],
                    [I(3, 1), S(1, 1), S(2, 0)],
                    [I(1, 2), I(2, 0), I(0, 1)],
                ],
            ),
            (_, 0b011) => (
                3,
                [
                    [c(0), m(0), c(2)],
                    [m(0), c(1), m(1)],
                    [m(0), m(1), c(2)],
                    [0; 3],
                ],
                [
                    [s(0, 0), I(2, 2), s(2, 0)],
                    [s(0, 1), s(1, 0), I(2, 0)],
                    [I(1, 2), s(1, 1), I(0, 1)],
                    none,
                ],
            ),
            (_, 0b101) => (
                3,
                [
                    [c(0), m(0), m(2)],
                    [m(2), m(0), c(2)],
                    [m(0), c(1), c(2)],
                    [0; 3],
                ],
                [
                    [s(0, 0), I(1, 0), s(2, 1)],
                    [I(0, 1), I(2, 2), s(2, 0)],
                    [s(0, 1), s(1, 0), I(1, 1)],
                    none,
                ],
            ),
            // Only the longest bisected (codes that break the closure never occur).
            _ => (
                2,
                [[c(0), m(0), c(2)], [m(0), c(1), c(2)], [0; 3], [0; 3]],
                [
                    [s(0, 0), I(1, 2), s(2, 0)],
                    [s(0, 1), s(1, 0), I(0, 1)],
                    none,
                    none,
                ],
            ),
        };
        let mut sides = [[0; 2]; 3];
        for (p, piece) in edges.iter().enumerate().take(count) {
            for (i, edge) in piece.iter().enumerate() {
                if let S(k, h) = *edge {
                    sides[k as usize][h as usize] = (3 * p + i) as u8;
                }
            }
        }
        Layout {
            count,
            pieces,
            edges,
            sides,
        }
    }

    /// The layouts of all codes (longest edge 0 to 2, any bisected edges), by code.
    fn all() -> [Layout; 24] {
        std::array::from_fn(|code| Layout::of(code as u8))
    }
}

/// `t` rotated so that its corner `k` comes first.
fn rotate(t: [u32; 3], k: usize) -> [u32; 3] {
    [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
}

/// Passes of Delaunay flips over the edges of the triangles that use a vertex from `first` on.
const FLIP_PASSES: usize = 3;
/// Largest dihedral angle (cosine) across an edge that may be flipped: the surface barely
/// changes where it is this flat.
const FLIP_FLATNESS: f32 = 0.98;

/// Flips edge `a b` of two triangles `a b c` and `b a d` to `c d` where the angles opposite it
/// sum to more than π (the Delaunay criterion) and the two triangles are nearly coplanar, in
/// passes whose flips share no vertex (so each pass is a function of the mesh, not of the
/// thread count or the order). Only edges of triangles using a vertex `>= first` are tried.
/// `twin`: the triangles' twins, which the flips keep up to date.
fn flip_around(vertices: &[Vec3], triangles: &mut [[u32; 3]], mut twin: Vec<[u32; 3]>, first: u32) {
    let mut locked = vec![false; vertices.len()];
    // Flips keep triangle numbers, so the triangles to try are found once.
    let mut near: Vec<u32> = (0..triangles.len() as u32)
        .into_par_iter()
        .with_min_len(CHUNK)
        .filter(|&f| triangles[f as usize].iter().any(|&v| v >= first))
        .collect();
    for _ in 0..FLIP_PASSES {
        let candidates: Vec<(u32, u32)> = near
            .par_iter()
            .with_min_len(CHUNK)
            .flat_map_iter(|&f| {
                let f = f as usize;
                let (twin, triangles) = (&twin, &*triangles);
                (0..3).filter_map(move |k| {
                    let c = (3 * f + k) as u32;
                    let other = twin[f][k];
                    (edge_id(c, other) == c && should_flip(vertices, triangles, c, other))
                        .then_some((c, other))
                })
            })
            .collect();
        locked.fill(false);
        let mut flipped = Vec::new();
        for (c, other) in candidates {
            let (f, k) = ((c / 3) as usize, (c % 3) as usize);
            let (g, j) = ((other / 3) as usize, (other % 3) as usize);
            let [a, b, cv] = rotate(triangles[f], k);
            let d = triangles[g][(j + 2) % 3];
            if [a, b, cv, d].iter().any(|&v| locked[v as usize])
                || !ring_lacks(triangles, &twin, (3 * f + (k + 2) % 3) as u32, d)
            {
                continue;
            }
            for v in [a, b, cv, d] {
                locked[v as usize] = true;
            }
            let outer = [
                twin[g][(j + 1) % 3], // a → d
                twin[f][(k + 2) % 3], // c → a
                twin[g][(j + 2) % 3], // d → b
                twin[f][(k + 1) % 3], // b → c
            ];
            let (f3, g3) = (3 * f as u32, 3 * g as u32);
            triangles[f] = [a, d, cv];
            triangles[g] = [d, b, cv];
            twin[f] = [outer[0], g3 + 2, outer[1]];
            twin[g] = [outer[2], outer[3], f3 + 1];
            for (o, corner) in outer.into_iter().zip([f3, f3 + 2, g3, g3 + 1]) {
                if o != NONE {
                    twin[(o / 3) as usize][(o % 3) as usize] = corner;
                }
            }
            flipped.extend([f as u32, g as u32]);
            flipped.extend(outer.iter().filter(|&&o| o != NONE).map(|&o| o / 3));
        }
        if flipped.is_empty() {
            return;
        }
        // The next pass tries the flipped quads and their neighbours, once each.
        flipped.sort_unstable();
        flipped.dedup();
        near = flipped;
    }
}

/// Whether no edge joins the vertex at corner `start` to `d`, walking the ring of that vertex
/// through the twins (false where the walk meets a boundary, so that nothing is assumed).
fn ring_lacks(triangles: &[[u32; 3]], twin: &[[u32; 3]], start: u32, d: u32) -> bool {
    let mut corner = start;
    for _ in 0..256 {
        let (f, k) = ((corner / 3) as usize, (corner % 3) as usize);
        if triangles[f][(k + 1) % 3] == d || triangles[f][(k + 2) % 3] == d {
            return false;
        }
        // The edge into this corner's vertex, prev → v, turned over: its twin starts at v.
        let back = twin[f][(k + 2) % 3];
        if back == NONE {
            return false;
        }
        corner = back;
        if corner == start {
            return true;
        }
    }
    false
}

/// Whether the edge at corner `c` (triangle `a b c'`), with its twin corner `other` (triangle
/// `b a d`), is non-Delaunay across a nearly flat fold and flipping it makes the smallest of
/// the pair's angles larger.
fn should_flip(vertices: &[Vec3], triangles: &[[u32; 3]], c: u32, other: u32) -> bool {
    let (f, k) = ((c / 3) as usize, (c % 3) as usize);
    let (g, j) = ((other / 3) as usize, (other % 3) as usize);
    let [a, b, cv] = rotate(triangles[f], k).map(|i| vertices[i as usize]);
    let d = vertices[triangles[g][(j + 2) % 3] as usize];
    // Two opposite angles γ at c' and δ at d sum to more than π only if one is obtuse: most
    // edges are rejected here, before any cross product.
    let (ca, cb, da, db) = (a - cv, b - cv, a - d, b - d);
    if ca.dot(cb) >= 0.0 && da.dot(db) >= 0.0 {
        return false;
    }
    let (n1, n2) = ((b - a).cross(cv - a), (a - b).cross(d - b));
    let dot = n1.dot(n2);
    if dot <= 0.0
        || dot * dot < FLIP_FLATNESS * FLIP_FLATNESS * n1.length_squared() * n2.length_squared()
    {
        return false;
    }
    // They sum to more than π iff sin(γ + δ) < 0, that is cos γ sin δ + sin γ cos δ < 0,
    // with each sine and cosine times its two edge lengths.
    if ca.dot(cb) * da.cross(db).length() + da.dot(db) * ca.cross(cb).length() >= 0.0 {
        return false;
    }
    let before = min_sine(a, b, cv).min(min_sine(b, a, d));
    let after = min_sine(a, d, cv).min(min_sine(d, b, cv));
    // The flipped pair must face the same way as before (no fold).
    let (m1, m2) = ((d - a).cross(cv - a), (b - d).cross(cv - d));
    after > before && m1.dot(n1) > 0.0 && m2.dot(n1) > 0.0
}

/// The sine of the smallest angle of the triangle `p q r` (the smallest of its three sines:
/// an obtuse angle's sine is that of the sum of the other two): twice its area over the product
/// of its two longest edges.
fn min_sine(p: Vec3, q: Vec3, r: Vec3) -> f32 {
    let mut l = [
        (q - p).length_squared(),
        (r - q).length_squared(),
        (p - r).length_squared(),
    ];
    l.sort_by(f32::total_cmp);
    let twice_area = (q - p).cross(r - p).length();
    twice_area / (l[1] * l[2]).sqrt().max(f32::MIN_POSITIVE)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::TriMesh;
    use crate::mesh::quality::bumpiness;
    use crate::mesh::topology::{normal_agreement, signed_volume, topology};
    use crate::tests::common::torus;

    fn refined(mesh: &TriMesh, degrees: f32) -> (TriMesh, Vec<u32>) {
        let mut out = mesh.clone();
        let rings = VertexFaces::new(out.vertices.len(), &out.triangles);
        let parents = refine_bends(
            &mut out.vertices,
            &mut out.normals,
            &mut out.triangles,
            rings,
            degrees.to_radians(),
        );
        (out, parents)
    }

    #[test]
    fn a_coarse_torus_is_refined_closed_and_rounder() {
        // 12 x 8 quads: 45° between rings of the tube, 30° around the axis.
        let mesh = torus(12, 8, 1.0, 0.3, 0.0);
        let (out, parents) = refined(&mesh, 20.0);
        let (a, b) = (topology(&mesh), topology(&out));
        assert!(b.is_closed_manifold(), "{b:?}");
        assert_eq!((b.components, b.euler_characteristic), (1, 0));
        assert_eq!(out.vertices.len(), mesh.vertices.len() + parents.len());
        assert_eq!(out.normals.len(), out.vertices.len());
        assert!(b.triangles > a.triangles);
        assert!(normal_agreement(&out) > 0.999);
        // Curved midpoints lie on the tube (radius 0.3 about the core circle) within 0.015, where
        // the chords' midpoints sag by 0.023 (across the tube) to 0.044 (around the axis); so
        // the volume nears the torus's 2π²Rr².
        let exact = 2.0 * std::f64::consts::PI.powi(2) * 1.0 * 0.09;
        let (v0, v1) = (signed_volume(&mesh), signed_volume(&out));
        assert!(
            (v1 - exact).abs() < (v0 - exact).abs(),
            "{v0} -> {v1} vs {exact}"
        );
        let tube = |p: Vec3| (Vec3::new(p.x, p.y, 0.0).normalize() - p).length();
        for p in &out.vertices[mesh.vertices.len()..] {
            assert!(
                (tube(*p) - 0.3).abs() < 0.015,
                "midpoint off the tube by {}",
                tube(*p) - 0.3
            );
        }
        assert!(bumpiness(&out) < bumpiness(&mesh));
    }

    /// Twins from a map of directed edges, the reference for the rows' pairing: an edge used
    /// once each way pairs, any other has no twin.
    fn twins_by_edges(triangles: &[[u32; 3]]) -> Vec<[u32; 3]> {
        let mut edges: std::collections::HashMap<(u32, u32), Vec<u32>> = Default::default();
        for (f, t) in triangles.iter().enumerate() {
            for k in 0..3 {
                let corner = (3 * f + k) as u32;
                edges
                    .entry((t[k], t[(k + 1) % 3]))
                    .or_default()
                    .push(corner);
            }
        }
        let twin = |a: u32, b: u32| match (edges[&(a, b)].as_slice(), edges.get(&(b, a))) {
            ([_], Some(back)) if back.len() == 1 => back[0],
            _ => NONE,
        };
        triangles
            .iter()
            .map(|t| std::array::from_fn(|k| twin(t[k], t[(k + 1) % 3])))
            .collect()
    }

    #[test]
    fn twins_pair_each_edge_used_once_each_way_and_no_other() {
        let closed = torus(12, 8, 1.0, 0.3, 0.0).triangles;
        // A hole (boundary edges), a triangle used twice (edges used twice one way) and one
        // that repeats a vertex.
        let mut broken = closed.clone();
        broken.remove(5);
        broken.push(broken[20]);
        broken.push([broken[40][0], broken[40][1], broken[40][0]]);
        for triangles in [closed, broken] {
            let n = 1 + triangles.iter().flatten().max().copied().unwrap_or(0) as usize;
            let rows = VertexFaces::new(n, &triangles);
            assert_eq!(twins(&triangles, rows), twins_by_edges(&triangles));
        }
    }

    #[test]
    fn the_bisected_meshs_twins_are_those_found_from_its_rows() {
        // A coarse torus with its vertices jittered, refined at several angles, meets every
        // layout: one, two (either pair) and three bisected edges.
        for degrees in [10.0, 20.0, 30.0, 45.0] {
            let mut mesh = torus(12, 8, 1.0, 0.3, 0.0);
            for (i, p) in mesh.vertices.iter_mut().enumerate() {
                let h = |k: u32| {
                    (((i as u32).wrapping_mul(2654435761) ^ k).wrapping_mul(40503) % 1000) as f32
                };
                *p += 0.00004 * Vec3::new(h(1), h(2), h(3));
            }
            let before = mesh.triangles.len();
            let rings = VertexFaces::new(mesh.vertices.len(), &mesh.triangles);
            let (parents, twin) = bisect(
                &mut mesh.vertices,
                &mut mesh.normals,
                &mut mesh.triangles,
                rings,
                f32::to_radians(degrees),
            );
            assert!(!parents.is_empty() && mesh.triangles.len() > before);
            let rows = VertexFaces::new(mesh.vertices.len(), &mesh.triangles);
            assert_eq!(twin, twins(&mesh.triangles, rows), "at {degrees}°");
        }
    }

    #[test]
    fn nothing_bends_more_than_the_angle_nothing_changes() {
        let mesh = torus(12, 8, 1.0, 0.3, 0.0);
        let (out, parents) = refined(&mesh, 60.0);
        assert!(parents.is_empty());
        assert_eq!(out, mesh);
    }

    #[test]
    fn an_open_edge_is_never_split() {
        // Two triangles of a folded strip, open all round: every edge but the shared one is a
        // boundary; the fold is split, the boundary edges are not.
        let mesh = TriMesh {
            vertices: vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(0.5, 1.0, 0.0),
                Vec3::new(0.5, -1.0, 1.0),
            ],
            normals: vec![Vec3::Z; 4],
            triangles: vec![[0, 1, 2], [1, 0, 3]],
        };
        let (out, parents) = refined(&mesh, 10.0);
        assert_eq!(parents.len(), 1);
        assert_eq!(out.triangles.len(), 4);
        assert_eq!(topology(&out).boundary_edges, 4);
    }
}
