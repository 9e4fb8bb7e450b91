//! The scalar field at every surface vertex (Sec. 4.1, "Scalar value computation"), gathered in
//! parallel: each brick collects the particles in reach once, each 2×2×2 group of vertices
//! narrows that list to its own reach in two steps, and each vertex sums over the short list.

use glam::{IVec3, Vec3};

use crate::error::Result;
use crate::field::{Sampled, ScalarField};
use crate::neighbours::handler_array::HandlerArray;
use crate::neighbours::neighbourhood::Neighbourhood;
use crate::recon::bricks::band::{BRICK, BRICK_VERTICES, Band, local_index};

pub use crate::recon::bricks::brick_values::BrickValues;

/// How far from zero, in cells, a field that can tell its sign first
/// ([`ScalarField::sign_first`]) must be settled for a vertex's value to be deferred. Only
/// performance depends on it: `deferred_values` samples whatever the triangles read. At
/// 1.5 cells 0.1 % of the deferred vertices were read on cbd-large at cell r/2 (2 % at 1
/// cell), and half of the band's vertices were deferred.
const DEFER_BEYOND_CELLS: f32 = 1.5;

/// The field at every vertex of `band`.
pub fn sample_field<F: ScalarField + ?Sized>(
    band: &Band,
    handlers: &HandlerArray,
    field: &F,
) -> Result<BrickValues> {
    Ok(sample(band, handlers, field, false)?.0)
}

/// [`sample_field`], leaving out the values of vertices whose sign the field settles far from
/// its surface (keeping a value of that sign); returns which, as bits per brick of `band`.
pub fn sample_field_deferring<F: ScalarField + ?Sized>(
    band: &Band,
    handlers: &HandlerArray,
    field: &F,
) -> Result<(BrickValues, Vec<[u64; 8]>)> {
    sample(band, handlers, field, true)
}

fn sample<F: ScalarField + ?Sized>(
    band: &Band,
    handlers: &HandlerArray,
    field: &F,
    defer: bool,
) -> Result<(BrickValues, Vec<[u64; 8]>)> {
    let cell = band.cell;
    let reach = field.support();
    let own_reach = field.reach_channel();
    let margin = DEFER_BEYOND_CELLS * cell;
    #[cfg(test)]
    let margin = tests::MARGIN_CELLS.get().map_or(margin, |m| m * cell);
    let sign_first = field.sign_first().filter(|_| defer);
    BrickValues::sample_with(
        band,
        || [(); 3].map(|_| Neighbourhood::default()),
        |[brick_near, block_near, group_near], b| {
            let (brick, mask) = (band.bricks[b], &band.masks[b]);
            let mut values = [f32::NAN; BRICK_VERTICES];
            let mut deferred = [0u64; 8];
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
                        if mask[l.z as usize] >> (i % 64) & 1 == 0 {
                            continue;
                        }
                        let x = (l - group).as_vec3() * cell;
                        let Some(sign_first) = sign_first else {
                            values[i] = field.value(group_near, x);
                            continue;
                        };
                        values[i] = match sign_first.value_or_sign(group_near, x, margin) {
                            Sampled::Value(v) => v,
                            Sampled::Beyond { inside } => {
                                deferred[i / 64] |= 1 << (i % 64);
                                // A value on the right side of zero, never zero.
                                let beyond = margin.max(f32::MIN_POSITIVE);
                                if inside { -beyond } else { beyond }
                            }
                        };
                    }
                }
            }
            (values, deferred)
        },
    )
}

/// Lowest corners of the cubes of side `step` tiling the cube of side `side` at `lo`.
pub(crate) fn cubes(lo: IVec3, side: i32, step: i32) -> impl Iterator<Item = IVec3> {
    let n = side / step;
    (0..n * n * n).map(move |k| lo + IVec3::new(k % n, k / n % n, k / (n * n)) * step)
}

/// Whether the cube of side `side` at local corner `lo` holds a band vertex.
pub(crate) fn has_vertices(mask: &[u64; 8], lo: IVec3, side: i32) -> bool {
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

#[cfg(test)]
pub(crate) mod tests {
    use std::cell::Cell;

    thread_local! {
        /// The deferring margin in cells, where a test sets one.
        pub static MARGIN_CELLS: Cell<Option<f32>> = const { Cell::new(None) };
    }
}
