//! The scalar field at every surface vertex (Sec. 4.1, "Scalar value computation"), gathered in
//! parallel: each brick collects the particles in reach once, each 2×2×2 group of vertices
//! narrows that list to its own reach in two steps, and each vertex sums over the short list.

use glam::{IVec3, Vec3};

use super::band::{BRICK, BRICK_VERTICES, Band, local_index};
use crate::error::Result;
use crate::field::ScalarField;
use crate::neighbours::handler_array::HandlerArray;
use crate::neighbours::neighbourhood::Neighbourhood;

pub use super::brick_values::BrickValues;

pub fn sample_field<F: ScalarField + ?Sized>(
    band: &Band,
    handlers: &HandlerArray,
    field: &F,
) -> Result<BrickValues> {
    let cell = band.cell;
    let reach = field.support();
    let own_reach = field.reach_channel();
    BrickValues::sample(
        band,
        || [(); 3].map(|_| Neighbourhood::default()),
        |[brick_near, block_near, group_near], b| {
            let (brick, mask) = (band.bricks[b], &band.masks[b]);
            let mut values = [f32::NAN; BRICK_VERTICES];
            let base = brick * BRICK;
            let corner = |l: IVec3| vertex_position(base + l, cell);
            brick_near.gather_box(
                handlers,
                corner(IVec3::ZERO),
                corner(IVec3::splat(BRICK - 1)),
                reach,
                own_reach,
            );
            // Two levels of narrowing, 4³ then 2³ vertices, keep each list within a few
            // percent of the particles really in reach.
            for block in cubes(IVec3::ZERO, BRICK, 4) {
                if !has_vertices(mask, block, 4) {
                    continue;
                }
                block_near.filter_box(
                    brick_near,
                    corner(block),
                    corner(block + 3),
                    reach,
                    own_reach,
                );
                for group in cubes(block, 4, 2) {
                    if !has_vertices(mask, group, 2) {
                        continue;
                    }
                    let glo = corner(group);
                    group_near.filter_box(block_near, glo, corner(group + 1), reach, own_reach);
                    for l in cubes(group, 2, 1) {
                        let i = local_index(l);
                        if mask[l.z as usize] >> (i % 64) & 1 == 1 {
                            let x = (l - group).as_vec3() * cell;
                            values[i] = field.value(group_near, x);
                        }
                    }
                }
            }
            values
        },
    )
}

/// Lowest corners of the cubes of side `step` tiling the cube of side `side` at `lo`.
fn cubes(lo: IVec3, side: i32, step: i32) -> impl Iterator<Item = IVec3> {
    let n = side / step;
    (0..n * n * n).map(move |k| lo + IVec3::new(k % n, k / n % n, k / (n * n)) * step)
}

/// Whether the cube of side `side` at local corner `lo` holds a band vertex.
fn has_vertices(mask: &[u64; 8], lo: IVec3, side: i32) -> bool {
    let row = ((1u64 << side) - 1) << lo.x;
    let plane = (0..side).fold(0, |p, y| p | row << (BRICK * (lo.y + y)));
    mask[lo.z as usize..(lo.z + side) as usize]
        .iter()
        .any(|w| w & plane != 0)
}

/// World position of grid vertex `v`.
pub fn vertex_position(v: IVec3, cell: f32) -> Vec3 {
    (v.as_dvec3() * f64::from(cell)).as_vec3()
}
