//! The field averaged along the flow (issue 38): near the surface, a vertex takes a weighted
//! mean ([`SIDE_WEIGHT`]) of frame t's field there and of frames t−1 and t+1's fields where the
//! fluid carries the vertex
//! (the cubic-spline mean, support 2r, of frame t's particles' displacements to them, as
//! `temporal::motion` takes it), read from the sides' own samples on the grid ([`SideField`])
//! by trilinear interpolation. What the field does as the particles rearrange, which their
//! mean motion does not carry, is shared with the frames beside it; a surface that moves with
//! the fluid stays where it is, within the interpolation's error.

use glam::{IVec3, Vec3};
use rayon::prelude::*;

use super::band_closure::Closed;
use super::field_sampling::{cubes, has_vertices, sample_field, vertex_position};
use super::side_field::SideField;
use super::side_field::{CORNERS, Lookup, Miss, cell_of_carried, corner_weights, value_at};
use crate::error::Result;
use crate::field::ScalarField;
use crate::field::radial_kernel::RadialKernel;
use crate::neighbours::handler_array::HandlerArray;
#[cfg(target_arch = "x86_64")]
use crate::neighbours::lane::F8;
use crate::neighbours::lane::Lane;
use crate::neighbours::lane_sums::{Lanes, lane_totals, lanes_path};
use crate::neighbours::neighbourhood::{LANES, Neighbourhood};
use crate::recon::bricks::band::{BRICK, Band, local_index, local_vertex};
use crate::recon::bricks::brick_values::{BrickValues, TASK_BRICKS};
use crate::recon::bricks::edge_tables::EdgeTables;

/// How near zero, in cells, a distance field's value must lie for its vertex to be averaged
/// although no crossed edge ends there: where the mean may bring in surface that frame t's
/// field lacks (a droplet the frames beside it hold). Measured on dense-dambreak 120–135,
/// `--temporal`: 0.0170 r carried with the ends alone, 0.0166 r at 0.5, 1 or 1.5 cells.
const NEAR_CELLS: f32 = 0.5;

/// Each side's share of the mean, frame t keeping the rest (0.4): the largest share measured
/// under which no face crosses another. Carried jitter with `--temporal` (following at reach
/// 3r, weight 0.4), dense-dambreak 120–135, all 40 frames, B2 and B3 (`bench/make-ball-pool.py`
/// with radius 0.01 and 0.0125): 0.28 gives 0.0145, 0.0140, 0.0127 and 0.0122 r; 0.3 0.0143,
/// 0.0140, 0.0124 and 0.0113 r; 1/3 0.0142, 0.0137 and 0.0120 r, but 7 faces of one of the 40
/// frames cross; 0.36 0.0142, 0.0137 and 0.0119 r, with faces crossing in one frame of the 40
/// and one of B2. The droplets make most of the difference.
const SIDE_WEIGHT: f32 = 0.3;

/// Rounds of averaging the ends of newly crossed edges at most (each round's mean can move
/// the surface across a vertex not averaged yet; two rounds sufficed on every frame measured).
const ROUNDS: usize = 8;

/// Frame t's particles with their moves, and the fields of frames t±1.
pub(crate) struct FlowMean<'a> {
    /// Channels: per side, the move's three coordinates and 1 where it is known (else 0).
    own: HandlerArray,
    sides: [SideField<'a>; 2],
    motion: RadialKernel,
}

impl<'a> FlowMean<'a> {
    /// `particles` with their `moves` to each side, with lookup cells of `lookup` (as the
    /// frame's handler array), and the sides' fields.
    pub fn new(
        particles: &[Vec3],
        moves: [&[Option<Vec3>]; 2],
        sides: [SideField<'a>; 2],
        spacing: f32,
        lookup: f32,
    ) -> Result<FlowMean<'a>> {
        let mut channels = Vec::with_capacity(8);
        for moves in moves {
            let d = |k: usize| moves.iter().map(|m| m.map_or(0.0, |d| d[k])).collect();
            channels.extend([d(0), d(1), d(2)]);
            channels.push(moves.iter().map(|m| f32::from(m.is_some() as u8)).collect());
        }
        Ok(FlowMean {
            own: HandlerArray::with_channels(particles, lookup, channels)?,
            sides,
            motion: RadialKernel::CubicSpline {
                support: 2.0 * spacing,
            },
        })
    }

    /// The bytes of its handler array.
    pub fn heap_bytes(&self) -> usize {
        self.own.heap_bytes()
    }

    /// Replaces the value at both ends of every edge that `closed` finds crossed by its mean
    /// along the flow, then closes the band again with `close` (which samples frame t's own
    /// field where the band grows and wherever a crossed edge reads a value left out, so that
    /// every end holds frame t's value first), until no crossed edge has an end left as
    /// sampled. Only the values the triangles read are averaged: elsewhere the sign alone
    /// counts, and averaging every vertex within 1.5 cells of zero took 2.6× the sampling's
    /// time for the same jitter. Returns how many vertices.
    pub fn average_crossed(
        &self,
        band: &mut Band,
        values: &mut BrickValues,
        closed: &mut Closed,
        field: &dyn ScalarField,
        mut close: impl FnMut(&mut Band, &mut BrickValues) -> Result<Closed>,
    ) -> Result<usize> {
        // Per brick of `band`, the vertices averaged so far.
        let mut done: Vec<[u64; 8]> = vec![[0; 8]; band.bricks.len()];
        let near = field.is_distance().then_some(NEAR_CELLS * band.cell);
        for round in 0..ROUNDS {
            let near = if round == 0 { near } else { None };
            let sub = round_vertices(band, values, &closed.tables, near, &done);
            if sub.bricks.is_empty() {
                break;
            }
            let means = self.means(&sub, band, values, field)?;
            values.overwrite(band, &sub, &means);
            for (brick, mask) in sub.bricks.iter().zip(&sub.masks) {
                let b = band.brick_index(*brick).expect("a band vertex's brick");
                for (d, m) in done[b].iter_mut().zip(mask) {
                    *d |= m;
                }
            }
            let before = band.bricks.clone();
            *closed = close(band, values)?;
            done = realigned(&before, done, band);
        }
        Ok(done.iter().flatten().map(|w| w.count_ones() as usize).sum())
    }

    /// The means along the flow at the vertices of `sub`, whose own values `values` holds
    /// on `band`: each side's field where the fluid carries a vertex, interpolated
    /// trilinearly from its values at the grid's vertices around that place (sampled as frame
    /// t's own field is sampled). At rest a vertex is its own corner, so a fluid at rest gets
    /// frame t's values to the bit; interpolating the grid's values rather than evaluating the
    /// sides' fields at the carried places themselves also shares the grid's own error with
    /// the frames beside, which cut dense-dambreak 120–135's carried jitter from 0.0157 to
    /// 0.0145 r (B2 0.0118 → 0.0123 r).
    fn means(
        &self,
        sub: &Band,
        band: &Band,
        values: &BrickValues,
        field: &dyn ScalarField,
    ) -> Result<BrickValues> {
        let carried = self.carried(sub);
        // Per vertex and side, the corners' weighted values that the side's own sampling
        // gave; the corners it left out or never reached (few) are sampled below.
        let mut known: Vec<(Vec<[f32; 2]>, Vec<Miss>)> = carried
            .par_iter()
            .with_max_len(TASK_BRICKS)
            .map_init(
                || self.sides.each_ref().map(Lookup::new),
                |lookups, list| {
                    let mut misses = Vec::new();
                    let sums = list
                        .iter()
                        .enumerate()
                        .map(|(k, &(v, m))| {
                            [0, 1].map(|side| {
                                let (c, f) = cell_of_carried(v, m[side], sub.cell);
                                let mut sum = 0.0;
                                for (w, o) in corner_weights(f).into_iter().zip(CORNERS) {
                                    if w == 0.0 {
                                        continue;
                                    }
                                    match lookups[side].value(c + o) {
                                        Some(x) => sum += w * x,
                                        None => misses.push(Miss {
                                            vertex: k as u32,
                                            side: side as u8,
                                            weight: w,
                                            corner: c + o,
                                        }),
                                    }
                                }
                                sum
                            })
                        })
                        .collect();
                    (sums, misses)
                },
            )
            .collect();
        let sampled = [0u8, 1].map(|side| {
            let mut corners: Vec<IVec3> = known
                .iter()
                .flat_map(|(_, misses)| misses.iter().filter(|m| m.side == side))
                .map(|m| m.corner)
                .collect();
            corners.par_sort_unstable_by_key(|v| (v.z, v.y, v.x));
            corners.dedup();
            let corners = Band::from_vertices(&corners, sub.cell);
            let values = sample_field(&corners, self.sides[side as usize].handlers, field)?;
            Ok::<_, crate::error::Error>((corners, values))
        });
        let [back, ahead] = sampled;
        let sampled = [back?, ahead?];
        known.par_iter_mut().for_each(|(sums, misses)| {
            for m in misses.iter() {
                let (corners, values) = &sampled[m.side as usize];
                sums[m.vertex as usize][m.side as usize] +=
                    m.weight * value_at(corners, values, m.corner);
            }
        });
        BrickValues::sample(
            sub,
            || (),
            |(), j| {
                let b = band
                    .brick_index(sub.bricks[j])
                    .expect("a band vertex's brick");
                let mut out = values.dense(&band.masks[b], b);
                for (&(v, _), &[back, ahead]) in carried[j].iter().zip(&known[j].0) {
                    let i = local_index(v - sub.bricks[j] * BRICK);
                    out[i] += ((back - out[i]) + (ahead - out[i])) * SIDE_WEIGHT;
                }
                out
            },
        )
    }

    /// Per brick of `sub`, each vertex with its moves to each side: the kernel means of frame
    /// t's particles' moves (zero for a side that no matched particle within 2r tells, which
    /// then counts as frame t's), gathered for the brick and narrowed twice.
    fn carried(&self, sub: &Band) -> Vec<Vec<(IVec3, [Vec3; 2])>> {
        let cell = sub.cell;
        let motion = self.motion.support();
        (0..sub.bricks.len())
            .into_par_iter()
            .with_max_len(TASK_BRICKS)
            .map_init(
                || [(); 3].map(|_| Neighbourhood::default()),
                |[brick_near, block_near, group_near], j| {
                    let (brick, mask) = (sub.bricks[j], &sub.masks[j]);
                    let base = brick * BRICK;
                    let at = |l: IVec3| vertex_position(base + l, cell);
                    let mut list = Vec::new();
                    let top = IVec3::splat(BRICK - 1);
                    brick_near.gather_box(&self.own, at(IVec3::ZERO), at(top), motion, None);
                    for block in cubes(IVec3::ZERO, BRICK, 4) {
                        if !has_vertices(mask, block, 4) {
                            continue;
                        }
                        block_near.filter_box(brick_near, at(block), at(block + 3), motion, None);
                        for group in cubes(block, 4, 2) {
                            if !has_vertices(mask, group, 2) {
                                continue;
                            }
                            group_near.filter_box(
                                block_near,
                                at(group),
                                at(group + 1),
                                motion,
                                None,
                            );
                            for l in cubes(group, 2, 1) {
                                let i = local_index(l);
                                if mask[i / 64] >> (i % 64) & 1 == 0 {
                                    continue;
                                }
                                let moves = self.moves(group_near, at(l) - group_near.anchor);
                                list.push((base + l, moves.map(|m| m.unwrap_or(Vec3::ZERO))));
                            }
                        }
                    }
                    list
                },
            )
            .collect()
    }

    /// The kernel means of the moves to each side of frame t's particles in `near` at `x`
    /// (relative to its anchor); None for a side that no matched particle within 2r tells.
    fn moves(&self, near: &Neighbourhood, x: Vec3) -> [Option<Vec3>; 2] {
        let lanes = match lanes_path() {
            // SAFETY: the CPU has AVX2, as `lanes_path` checked.
            #[cfg(target_arch = "x86_64")]
            Lanes::Avx2 | Lanes::Avx512 => unsafe { motion_avx2(near, x, &self.motion) },
            _ => motion_lanes::<f32>(near, x, &self.motion),
        };
        let sums = lane_totals(&lanes);
        [0, 4].map(|k| {
            (sums[k + 3] > 0.0).then(|| Vec3::new(sums[k], sums[k + 1], sums[k + 2]) / sums[k + 3])
        })
    }
}

/// Per side, Σ w·known·move and Σ w·known over `near` at `x` (w the cubic spline), in
/// `LANES` lanes, the same bits one lane or eight at a time.
#[inline(always)]
fn motion_lanes<L: Lane>(
    near: &Neighbourhood,
    x: Vec3,
    kernel: &RadialKernel,
) -> [[f32; LANES]; 8] {
    let mut acc = [[0.0f32; LANES]; 8];
    let at = [L::splat(x.x), L::splat(x.y), L::splat(x.z)];
    let c = &near.channels;
    let mut i = 0;
    while i + LANES <= near.len() {
        for part in (0..LANES).step_by(L::WIDTH) {
            let j = i + part;
            let (dx, dy, dz) = (
                L::load(&near.x[j..]) - at[0],
                L::load(&near.y[j..]) - at[1],
                L::load(&near.z[j..]) - at[2],
            );
            let w = kernel.weight(dx * dx + dy * dy + dz * dz);
            for side in [0, 4] {
                let k = w * L::load(&c[side + 3][j..]);
                for a in 0..3 {
                    let sum = L::load(&acc[side + a][part..]) + k * L::load(&c[side + a][j..]);
                    sum.store(&mut acc[side + a][part..]);
                }
                (L::load(&acc[side + 3][part..]) + k).store(&mut acc[side + 3][part..]);
            }
        }
        i += LANES;
    }
    acc
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn motion_avx2(near: &Neighbourhood, x: Vec3, kernel: &RadialKernel) -> [[f32; LANES]; 8] {
    motion_lanes::<F8>(near, x, kernel)
}

/// The vertices to average in a round, as a sub-band of `band`: both ends of each edge that
/// `tables` holds, with `near` also the vertices whose values lie within it of zero, less
/// those in `done` (per brick of `band`). An edge's far end lies in its brick or the next one
/// along the edge, so each brick gathers its own ends and those its lower neighbours pass on.
fn round_vertices(
    band: &Band,
    values: &BrickValues,
    tables: &EdgeTables,
    near: Option<f32>,
    done: &[[u64; 8]],
) -> Band {
    // Per brick: its own vertices, and those past its +x, +y and +z faces.
    let own: Vec<[[u64; 8]; 4]> = (0..band.bricks.len())
        .into_par_iter()
        .with_max_len(TASK_BRICKS)
        .map(|b| {
            let mut out = [[0u64; 8]; 4];
            let mut put = |l: IVec3| {
                let past = (0..3).find(|&a| l[a] == BRICK).map_or(0, |a| a + 1);
                let l = l - if past > 0 {
                    IVec3::AXES[past - 1] * BRICK
                } else {
                    IVec3::ZERO
                };
                let i = local_index(l);
                out[past][i / 64] |= 1 << (i % 64);
            };
            if let Some(edges) = tables.0[b].as_deref() {
                edges.each(|local, axis| {
                    let l = local_vertex(local);
                    put(l);
                    put(l + IVec3::AXES[axis]);
                });
            }
            if let Some(limit) = near {
                let dense = values.dense(&band.masks[b], b);
                for (i, v) in dense.iter().enumerate() {
                    if v.abs() < limit {
                        out[0][i / 64] |= 1 << (i % 64);
                    }
                }
            }
            out
        })
        .collect();
    let (bricks, masks): (Vec<IVec3>, Vec<[u64; 8]>) = band
        .bricks
        .par_iter()
        .enumerate()
        .filter_map(|(b, &brick)| {
            let mut mask = own[b][0];
            for a in 0..3 {
                if let Some(n) = band.brick_index(brick - IVec3::AXES[a]) {
                    for (m, w) in mask.iter_mut().zip(own[n][a + 1]) {
                        *m |= w;
                    }
                }
            }
            for (m, d) in mask.iter_mut().zip(done[b]) {
                *m &= !d;
            }
            mask.iter().any(|&w| w != 0).then_some((brick, mask))
        })
        .unzip();
    Band::from_masks(band.cell, bricks, masks)
}

/// `done`, per brick of the band whose bricks were `before`, per brick of `band` (which holds
/// those bricks and maybe more: both in (z, y, x) order).
fn realigned(before: &[IVec3], done: Vec<[u64; 8]>, band: &Band) -> Vec<[u64; 8]> {
    if before.len() == band.bricks.len() {
        return done;
    }
    let mut out = vec![[0u64; 8]; band.bricks.len()];
    for (brick, mask) in before.iter().zip(done) {
        out[band
            .brick_index(*brick)
            .expect("closing a band keeps its bricks")] = mask;
    }
    out
}
