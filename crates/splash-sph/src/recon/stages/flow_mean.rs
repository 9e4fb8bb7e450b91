//! The field averaged along the flow (issue 38): near the surface, a vertex takes a weighted
//! mean ([`SIDE_WEIGHT`]) of frame t's field there and of frames t−1 and t+1's fields where the
//! fluid carries the vertex
//! (the cubic-spline mean, support 2r, of frame t's particles' displacements to them, as
//! `temporal::motion` takes it). What the field does as the particles rearrange, which their
//! mean motion does not carry, is shared with the frames beside it; a surface that moves with
//! the fluid stays where it is.

use std::ops::Range;

use glam::{IVec3, Vec3};
use rayon::prelude::*;
use rustc_hash::FxHashSet;

use super::band_closure::Closed;
use super::field_sampling::{cubes, has_vertices, vertex_position};
use crate::error::Result;
use crate::field::ScalarField;
use crate::field::radial_kernel::RadialKernel;
use crate::neighbours::handler_array::HandlerArray;
#[cfg(target_arch = "x86_64")]
use crate::neighbours::lane::F8;
use crate::neighbours::lane::Lane;
use crate::neighbours::lane_sums::{Lanes, lane_totals, lanes_path};
use crate::neighbours::neighbourhood::{LANES, Neighbourhood};
use crate::recon::bricks::band::{BRICK, BRICK_VERTICES, Band, local_index, local_vertex};
use crate::recon::bricks::brick_values::BrickValues;
use crate::recon::bricks::edge_tables::EdgeTables;

/// Frames t−1 and t+1 beside the frame reconstructed, for [`FlowMean`].
#[derive(Debug, Clone, Copy)]
pub struct Sides<'a> {
    /// Their particles.
    pub particles: [&'a [Vec3]; 2],
    /// Each of frame t's particles' displacement to each; None where it has no match there.
    pub moves: [&'a [Option<Vec3>]; 2],
}

/// How near zero, in cells, a distance field's value must lie for its vertex to be averaged
/// although no crossed edge ends there: where the mean may bring in surface that frame t's
/// field lacks (a droplet the frames beside it hold). Measured on dense-dambreak 120–135,
/// `--temporal`: 0.0170 r carried with the ends alone, 0.0166 r at 0.5, 1 or 1.5 cells.
const NEAR_CELLS: f32 = 0.5;

/// Each side's share of the mean, frame t keeping the rest (0.44). Carried jitter with
/// `--temporal` (following at reach 3r, weight 0.4), dense-dambreak 120–135, all 40 frames
/// and B2: 0.28 gives 0.0157, 0.0148 and 0.0118 r; 1/3 (the three frames alike) 0.0164, 0.0152
/// and 0.0119 r; 0.25 0.0160 and 0.0121 r (120–135, B2); 0.2 0.0161 and 0.0123 r; 0.4 0.0165 and
/// 0.0116 r. The droplets make most of the difference (120–135: 0.0666 against 0.0729 r).
const SIDE_WEIGHT: f32 = 0.28;

/// Rounds of averaging the ends of newly crossed edges at most (each round's mean can move
/// the surface across a vertex not averaged yet; two rounds sufficed on every frame measured).
const ROUNDS: usize = 8;

/// Frame t's particles with their moves, and frames t±1's particles with the field's channels.
pub(crate) struct FlowMean {
    /// Channels: per side, the move's three coordinates and 1 where it is known (else 0).
    own: HandlerArray,
    sides: [HandlerArray; 2],
    motion: RadialKernel,
}

impl FlowMean {
    /// `particles` and `sides` with lookup cells of `lookup` (as the frame's handler array).
    pub fn new(
        particles: &[Vec3],
        sides: &Sides<'_>,
        field: &dyn ScalarField,
        spacing: f32,
        lookup: f32,
    ) -> Result<FlowMean> {
        let mut channels = Vec::with_capacity(8);
        for moves in sides.moves {
            let d = |k: usize| moves.iter().map(|m| m.map_or(0.0, |d| d[k])).collect();
            channels.extend([d(0), d(1), d(2)]);
            channels.push(moves.iter().map(|m| f32::from(m.is_some() as u8)).collect());
        }
        let own = HandlerArray::with_channels(particles, lookup, channels)?;
        let side = |p: &[Vec3]| -> Result<HandlerArray> {
            let mut h = HandlerArray::new(p, lookup)?;
            h.channels = field.particle_channels(&h);
            Ok(h)
        };
        Ok(FlowMean {
            own,
            sides: [side(sides.particles[0])?, side(sides.particles[1])?],
            motion: RadialKernel::CubicSpline {
                support: 2.0 * spacing,
            },
        })
    }

    /// The bytes of its three handler arrays.
    pub fn heap_bytes(&self) -> usize {
        self.own.heap_bytes()
            + self
                .sides
                .iter()
                .map(HandlerArray::heap_bytes)
                .sum::<usize>()
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
        let mut done: FxHashSet<IVec3> = FxHashSet::default();
        let near = field.is_distance().then_some(NEAR_CELLS * band.cell);
        for round in 0..ROUNDS {
            let mut ends = crossed_ends(band, &closed.tables, &done);
            if let (0, Some(near)) = (round, near) {
                // Some are ends too: the sub-band and `done` take each vertex once.
                ends.extend(near_zero(band, values, near));
            }
            if ends.is_empty() {
                break;
            }
            let sub = Band::from_vertices(&ends, band.cell);
            let means = self.means(&sub, band, values, field)?;
            values.overwrite(band, &sub, &means);
            done.extend(ends);
            *closed = close(band, values)?;
        }
        Ok(done.len())
    }

    /// The means along the flow at the vertices of `sub`, whose own values `values` holds
    /// on `band`.
    fn means(
        &self,
        sub: &Band,
        band: &Band,
        values: &BrickValues,
        field: &dyn ScalarField,
    ) -> Result<BrickValues> {
        let cell = band.cell;
        let (support, reach) = (field.support(), field.reach_channel());
        let motion = self.motion.support();
        BrickValues::sample(sub, Scratch::default, |scratch, j| {
            let Scratch {
                near,
                carried,
                groups,
            } = scratch;
            let (brick, mask) = (sub.bricks[j], &sub.masks[j]);
            let b = band.brick_index(brick).expect("a band vertex's brick");
            let mut out = values.dense(&band.masks[b], b);
            let base = brick * BRICK;
            let at = |l: IVec3| vertex_position(base + l, cell);
            // Each 4³ block's and 2³ group's vertices, in that order, with their moves from
            // the particles near the group (gathered for the brick, narrowed twice).
            for c in &mut *carried {
                c.clear();
            }
            groups.clear();
            let [brick_near, block_near, group_near] = near;
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
                    group_near.filter_box(block_near, at(group), at(group + 1), motion, None);
                    let first = carried[0].len();
                    for l in cubes(group, 2, 1) {
                        let i = local_index(l);
                        if mask[i / 64] >> (i % 64) & 1 == 0 {
                            continue;
                        }
                        let moves = self.moves(group_near, at(l) - group_near.anchor);
                        for (list, m) in carried.iter_mut().zip(moves) {
                            // A side that no particle's motion reaches counts as frame t's.
                            list.push((l, m.unwrap_or(Vec3::ZERO)));
                        }
                    }
                    groups.push((block, group, first..carried[0].len()));
                }
            }
            // Each side's field where the vertices are carried, gathered as the sampling
            // gathers frame t's (brick, block, group) over boxes grown to hold the carried
            // places: where the frames agree, the same particles in the same order give
            // frame t's value to the bit, and the mean adds each side's difference from it.
            let mut sums = [0.0f32; BRICK_VERTICES];
            let grown = |lo: IVec3, hi: IVec3, list: &[(IVec3, Vec3)]| {
                let (a, b) = bounds(list.iter().map(|&(l, m)| at(l) + m)).expect("vertices");
                (at(lo).min(a), at(hi).max(b))
            };
            for (side, list) in carried.iter().enumerate() {
                let (lo, hi) = grown(IVec3::ZERO, top, list);
                brick_near.gather_box(&self.sides[side], lo, hi, support, reach);
                let mut block = None;
                for (k, (b, group, range)) in groups.iter().enumerate() {
                    if block != Some(*b) {
                        block = Some(*b);
                        let last = groups[k..].iter().take_while(|(c, ..)| c == b).last();
                        let all = range.start..last.map_or(range.end, |(.., r)| r.end);
                        let (lo, hi) = grown(*b, *b + 3, &list[all]);
                        block_near.filter_box(brick_near, lo, hi, support, reach);
                    }
                    let (lo, hi) = grown(*group, *group + 1, &list[range.clone()]);
                    group_near.filter_box(block_near, lo, hi, support, reach);
                    // As the sampling places a vertex in its group, plus the move.
                    let shift = at(*group) - lo;
                    for &(l, m) in &list[range.clone()] {
                        let x = (l - *group).as_vec3() * cell + shift + m;
                        let i = local_index(l);
                        sums[i] += field.value(group_near, x) - out[i];
                    }
                }
            }
            for (i, (v, sum)) in out.iter_mut().zip(sums).enumerate() {
                if mask[i / 64] >> (i % 64) & 1 == 1 {
                    *v += sum * SIDE_WEIGHT;
                }
            }
            out
        })
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

/// The box around `points`, if any.
fn bounds(points: impl Iterator<Item = Vec3>) -> Option<(Vec3, Vec3)> {
    points.fold(None, |b, p| match b {
        None => Some((p, p)),
        Some((lo, hi)) => Some((p.min(lo), p.max(hi))),
    })
}

/// The vertices of `band` whose values lie within `limit` of zero.
fn near_zero(band: &Band, values: &BrickValues, limit: f32) -> Vec<IVec3> {
    (0..band.bricks.len())
        .into_par_iter()
        .flat_map_iter(|b| {
            let dense = values.dense(&band.masks[b], b);
            let base = band.bricks[b] * BRICK;
            (0..BRICK_VERTICES)
                .filter(move |&i| dense[i].abs() < limit)
                .map(move |i| base + local_vertex(i))
        })
        .collect()
}

/// Both ends of each edge that `tables` holds on `band`, but those in `done`; sorted.
fn crossed_ends(band: &Band, tables: &EdgeTables, done: &FxHashSet<IVec3>) -> Vec<IVec3> {
    let mut ends: Vec<IVec3> = tables
        .0
        .par_iter()
        .enumerate()
        .filter_map(|(b, t)| t.as_deref().map(|t| (b, t)))
        .flat_map_iter(|(b, edges)| {
            let base = band.bricks[b] * BRICK;
            let mut out = Vec::new();
            edges.each(|local, axis| {
                let l = base + local_vertex(local);
                out.extend(
                    [l, l + IVec3::AXES[axis]]
                        .into_iter()
                        .filter(|v| !done.contains(v)),
                );
            });
            out
        })
        .collect();
    ends.par_sort_unstable_by_key(|v| (v.z, v.y, v.x));
    ends.dedup();
    ends
}

/// One task's buffers, reused from brick to brick.
#[derive(Default)]
struct Scratch {
    /// Particles near the brick, a 4³ block and a 2³ group.
    near: [Neighbourhood; 3],
    /// Per side, each vertex (local coordinates) and its move there.
    carried: [Vec<(IVec3, Vec3)>; 2],
    /// Each group's block, its lowest vertex and its vertices' range in `carried`.
    groups: Vec<(IVec3, IVec3, Range<usize>)>,
}
