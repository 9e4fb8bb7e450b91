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

use crate::neighbours::handler_array::HandlerArray;
use crate::neighbours::neighbourhood;

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
) -> Vec<Block> {
    // A margin covering the reach, plus one cube so that no particle's nearest corner lies on
    // the forced boundary.
    let margin = (reach / cell).ceil() as i32 + 1;
    let cube = |p: Vec3| (p / cell).floor().as_ivec3();
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
    keys.into_par_iter()
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
        .collect()
}
