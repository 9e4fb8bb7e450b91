//! Block subdivision (Rosenberg & Birdwell 2008, Sec. 3): the grid's cubes are cut into blocks
//! of `size`³ cubes; each is marched over its cubes plus a margin of cubes covering the reach,
//! with the field forced outside on the margin's outer boundary so that every surface in it is
//! closed. A block keeps the particles within reach of its margin too (the paper keeps those
//! within reach of its cubes): the margin's field is then exact, and a surface that dips into
//! the margin is still found from the particles there. With only the paper's particles, a
//! margin corner can miss a particle, read outside, and cut a surface off from its seeds: on
//! fixtures/frame_0040 with blocks of 7 cubes that left a hole in a block's face.

use glam::{IVec3, Vec3};
use rayon::prelude::*;
use rustc_hash::FxHashSet;

use super::lookup_cache::LookupCache;
use crate::config::Params;
use crate::error::Result;
use crate::field::ScalarField;
use crate::neighbours::handler_array::HandlerArray;
use crate::neighbours::neighbourhood;
use crate::recon::budget::{self, mul};
use crate::report::{Stage, Stages};

pub struct Block {
    /// Global index of the block's first cube (cube k spans corners k to k + 1).
    pub lo: IVec3,
    /// Cubes per side, without the margin.
    pub size: i32,
    /// Cubes of margin on each side.
    pub margin: i32,
    /// Handler indices of the particles within reach of the block's cubes and margin, by
    /// height.
    pub particles: Vec<u32>,
}

impl Block {
    pub fn heap_bytes(&self) -> usize {
        self.particles.capacity() * size_of::<u32>()
    }

    /// An upper estimate of the heap its marching holds at its peak, with `channels`
    /// per-particle channels, a reach of `reach` cubes and the mesh aside: the lookup cache
    /// (as if its window held all the particles), the block's copies of its particles and the
    /// seeds' walks from them, four slice caches (the paper's two, with their neighbours; 3 at
    /// most on the fixtures), and the missed seeds' bits and brick layer.
    pub fn planned_bytes(&self, channels: usize, reach: f32) -> u64 {
        block_bytes(
            self.particles.len() as u64,
            self.size + 2 * self.margin,
            channels,
            reach,
        )
    }
}

/// [`Block::planned_bytes`] of a block of `cubes` per side with its margins, holding
/// `particles`.
pub fn block_bytes(particles: u64, cubes: i32, channels: usize, reach: f32) -> u64 {
    let side = (cubes.max(0) + 1) as u64;
    let columns = side * side;
    let cache = LookupCache::planned_bytes(particles, cubes, f64::from(reach));
    // Positions and channels, the block's list, and the seeds' walks (48 a particle).
    let copies = particles.saturating_mul(12 + 4 * channels as u64 + 4 + 48);
    let slices = 4 * columns * 4 + 3 * columns * 4;
    // The visited bits, and the missed seeds' layer of bricks: its marks, vertices (12),
    // values as sampled (4) and as planes (4), on 9 planes at most.
    let seeds = side.pow(3) / 8 + 9 * columns * (12 + 4 + 4);
    cache
        .saturating_add(copies)
        .saturating_add(slices)
        .saturating_add(seeds)
}

/// Cubes of margin on each side of a block, for a reach of `reach` world units.
pub fn margin(reach: f32, cell: f32) -> i32 {
    (reach / cell).ceil() as i32 + 1
}

/// The most particles found in a block's box (its cubes, margins and reach) centred on one of
/// 64 particles spread over the handler order: an estimate of the fullest block, made before
/// the blocks are built (which takes memory of its own).
pub fn fullest_block_guess(handlers: &HandlerArray, reach: f32, cell: f32, size: i32) -> u64 {
    let n = handlers.positions.len();
    let half = (size + 2 * margin(reach, cell)) as f32 * cell / 2.0 + reach;
    (0..n)
        .step_by((n / 64).max(1))
        .collect::<Vec<_>>()
        .par_iter()
        .map(|&i| {
            let p = handlers.positions[i];
            let mut count = 0u64;
            handlers.for_each_in_box(p - half, p + half, |r| count += r.len() as u64);
            count
        })
        .max()
        .unwrap_or(0)
}

/// [`subdivide`] of `samples` into blocks of `params.block` cubes a side, in the band stage,
/// the key sets and particle lists (about 24 bytes a pair) checked against the memory limit
/// with `held` bytes besides them: the blocks of the slices engine and of the
/// surface-following baselines.
pub fn subdivide_within_limit(
    stages: &mut Stages<'_>,
    params: &Params,
    field: &dyn ScalarField,
    samples: &HandlerArray,
    held: u64,
) -> Result<Vec<Block>> {
    let n = samples.positions.len();
    stages.run(Stage::Band, || {
        subdivide(
            samples,
            field.support(),
            field.reach_channel(),
            params.cell,
            params.block as i32,
            |pairs| {
                let need = held.saturating_add(mul(pairs, 24));
                budget::check(params, need, || {
                    format!(
                        "the blocks of {n} particles ({pairs} pairs of a block of {}³ cubes and \
                         a particle reaching it)",
                        params.block
                    )
                })
                .map(drop)
            },
        )
    })
}

/// The blocks whose cubes some particle reaches, in (z, y, x) order, with their particles. `reach`
/// is the field's support; with `own_reach`, a particle reaches the smaller of it and its
/// value in that channel.
pub fn subdivide(
    handlers: &HandlerArray,
    reach: f32,
    own_reach: Option<usize>,
    cell: f32,
    size: i32,
    budget: impl FnOnce(u64) -> Result<()>,
) -> Result<Vec<Block>> {
    // A margin covering the reach, plus one cube so that no particle's nearest corner lies on
    // the forced boundary.
    let margin = margin(reach, cell);
    let cube = |p: Vec3| (p / cell).floor().as_ivec3();
    // The (block, particle) pairs of the key sets, before they are built.
    let pairs = handlers
        .positions
        .par_iter()
        .map(|&p| {
            let (a, b) = (cube(p - reach), cube(p + reach));
            let n = b.div_euclid(IVec3::splat(size)) - a.div_euclid(IVec3::splat(size)) + 1;
            n.to_array()
                .iter()
                .fold(1u64, |a, &k| a.saturating_mul(k.max(0) as u64))
        })
        .reduce(|| 0, u64::saturating_add);
    budget(pairs)?;
    let mut keys: Vec<IVec3> = handlers
        .positions
        .par_iter()
        .fold(FxHashSet::default, |mut set, &p| {
            let (a, b) = (cube(p - reach), cube(p + reach));
            let (a, b) = (
                a.div_euclid(IVec3::splat(size)),
                b.div_euclid(IVec3::splat(size)),
            );
            for z in a.z..=b.z {
                for y in a.y..=b.y {
                    for x in a.x..=b.x {
                        set.insert(IVec3::new(x, y, z));
                    }
                }
            }
            set
        })
        .reduce(FxHashSet::default, |mut a, b| {
            a.extend(b);
            a
        })
        .into_iter()
        .collect();
    keys.sort_unstable_by_key(|k| (k.z, k.y, k.x));
    Ok(keys
        .into_par_iter()
        .map(|key| {
            let lo = key * size;
            let box_lo = (lo - margin).as_vec3() * cell;
            let box_hi = (lo + size + margin).as_vec3() * cell;
            let particle_reach = neighbourhood::reach(&handlers.channels, reach, own_reach);
            let mut particles = Vec::new();
            handlers.for_each_in_box(box_lo - reach, box_hi + reach, |range| {
                for i in range {
                    let p = handlers.positions[i];
                    let r = particle_reach(i);
                    if (p - p.clamp(box_lo, box_hi)).length_squared() <= r * r {
                        particles.push(i as u32);
                    }
                }
            });
            let z = |i: &u32| handlers.positions[*i as usize].z;
            particles.sort_unstable_by(|a, b| z(a).total_cmp(&z(b)).then(a.cmp(b)));
            particles.shrink_to_fit();
            Block {
                lo,
                size,
                margin,
                particles,
            }
        })
        .filter(|b| !b.particles.is_empty())
        .collect())
}
