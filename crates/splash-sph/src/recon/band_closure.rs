//! Closing the band where the surface leaves it.
//!
//! The band of Sec. 4.1 holds the surface only where the surface stays near surface particles.
//! SSP07 can bridge two splash particles about 2.5r apart with a surface whose middle lies
//! beyond 2r of both, and a cell there lacks corners: a hole. Here the surface is followed out
//! of the band instead: wherever a triangulated cell's face is crossed by the surface and the
//! cell beyond it is incomplete, that cell's missing corners join the band, until none is
//! missing. The surface is closed by construction, and the band grows only where it has to.

use glam::IVec3;
use rayon::prelude::*;

use super::band::{BRICK, Band};
use super::brick_neighbours::NeighbourWalk;
use super::brick_signs::Signs;
use super::field_sampling::BrickValues;
use super::halo::offset;
use super::surface_cells::BrickCells;
use crate::error::Result;

/// Grows the band until no surface cell has an open face; `sample` gives the field on a band
/// of new vertices, told how many bricks the band will have at most with them (to check the
/// memory limit as the band grows). Returns the number of vertices added, and the sign planes
/// of the closed band.
pub fn close_band(
    band: &mut Band,
    values: &mut BrickValues,
    mut sample: impl FnMut(&Band, usize) -> Result<BrickValues>,
) -> Result<(usize, Signs)> {
    let mut added = 0;
    let mut scan = band.bricks.clone();
    loop {
        let signs = Signs::of(band, values);
        let missing = missing_vertices(band, &signs, &scan);
        if missing.is_empty() {
            return Ok((added, signs));
        }
        drop(signs);
        added += missing.len();
        let grown = Band::from_vertices(&missing, band.cell);
        // Only cells near the new vertices can have new open faces.
        scan = grown
            .bricks
            .iter()
            .flat_map(|&b| (0..27).map(move |n| b + IVec3::new(n % 3, n / 3 % 3, n / 9) - 1))
            .collect();
        let grown_values = sample(&grown, band.bricks.len() + grown.bricks.len())?;
        band.merge(values, grown, grown_values)?;
        scan.sort_unstable_by_key(|b| (b.z, b.y, b.x));
        scan.dedup();
        scan.retain(|&b| band.brick_index(b).is_some());
    }
}

/// Grid vertices that must join the band, found in the bricks `scan`, sorted and without
/// repeats.
fn missing_vertices(band: &Band, signs: &Signs, scan: &[IVec3]) -> Vec<IVec3> {
    let mut missing: Vec<IVec3> = scan
        .par_iter()
        .map_init(
            || (BrickCells::new(), NeighbourWalk::new(&band.bricks)),
            |(cells, walk), &brick| {
                let mut out = Vec::new();
                let neighbours = walk.around(brick);
                if signs.owns_inside_corner(&neighbours) {
                    cells.fill(band, signs, neighbours);
                    open_faces(cells, brick * BRICK, &mut out);
                }
                out
            },
        )
        .flatten()
        .collect();
    missing.par_sort_unstable_by_key(|v| (v.z, v.y, v.x));
    missing.dedup();
    missing
}

/// Appends the missing corners of the incomplete cells across the crossed faces of the
/// brick's crossed cells.
fn open_faces(cells: &BrickCells, base: IVec3, out: &mut Vec<IVec3>) {
    cells.crossed(|l, case| {
        for axis in 0..3 {
            for side in 0..2 {
                if !BrickCells::face_crossed(case, axis, side) {
                    continue;
                }
                let step = if side == 1 { 1 } else { -1 };
                let beyond = l + IVec3::AXES[axis] * step;
                if cells.complete(beyond) {
                    continue;
                }
                for c in 0..8 {
                    let v = beyond + offset(c);
                    if !cells.present(v) {
                        out.push(base + v);
                    }
                }
            }
        }
    });
}
