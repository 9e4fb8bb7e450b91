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

use crate::error::Result;
use crate::recon::bricks::band::{BRICK, Band};
use crate::recon::bricks::brick_neighbours::NeighbourWalk;
use crate::recon::bricks::brick_signs::Signs;
use crate::recon::bricks::brick_values::{self, BrickValues};
use crate::recon::bricks::edge_tables::{self, EdgeTables};
use crate::recon::bricks::halo::offset;
use crate::recon::bricks::surface_cells::BrickCells;

/// The band once closed: the vertices closure added, the sign planes of its values and the
/// edge tables of its bricks.
#[derive(Clone)]
pub struct Closed {
    pub added: usize,
    pub signs: Signs,
    pub tables: EdgeTables,
}

/// Grows the band until no surface cell has an open face; `sample` gives the field on a band
/// of new vertices, told how many bricks the band will have at most with them (to check the
/// memory limit as the band grows).
pub fn close_band(
    band: &mut Band,
    values: &mut BrickValues,
    mut sample: impl FnMut(&Band, usize) -> Result<BrickValues>,
) -> Result<Closed> {
    let mut added = 0;
    let mut tables = EdgeTables((0..band.bricks.len()).map(|_| None).collect());
    let mut scan = vec![true; band.bricks.len()];
    loop {
        let signs = Signs::of(band, values);
        let missing = scan_bricks(band, &signs, &scan, &mut tables);
        if missing.is_empty() {
            return Ok(Closed {
                added,
                signs,
                tables,
            });
        }
        drop(signs);
        added += missing.len();
        let grown = Band::from_vertices(&missing, band.cell);
        let grown_bricks = grown.bricks.clone();
        let grown_values = sample(&grown, band.bricks.len() + grown.bricks.len())?;
        let old = band.bricks.clone();
        brick_values::merge(band, values, grown, grown_values)?;
        tables = tables.regrid(&old, &band.bricks);
        // Only cells near the new vertices can have new open faces, or new edge tables.
        scan = vec![false; band.bricks.len()];
        for b in grown_bricks {
            for n in 0..27 {
                if let Some(i) = band.brick_index(b + IVec3::new(n % 3, n / 3 % 3, n / 9) - 1) {
                    scan[i] = true;
                }
            }
        }
    }
}

/// Scans the bricks that `scan` flags: sets their edge tables in `tables`, and returns the
/// grid vertices that must join the band, sorted and without repeats.
fn scan_bricks(band: &Band, signs: &Signs, scan: &[bool], tables: &mut EdgeTables) -> Vec<IVec3> {
    let mut missing: Vec<IVec3> = tables
        .0
        .par_iter_mut()
        .zip(scan)
        .enumerate()
        .filter(|(_, (_, scan))| **scan)
        .map_init(
            || (BrickCells::new(), NeighbourWalk::new(&band.bricks)),
            |(cells, walk), (b, (table, _))| {
                let mut out = Vec::new();
                let brick = band.bricks[b];
                let neighbours = walk.around(brick);
                *table = None;
                if signs.owns_inside_corner(&neighbours) {
                    cells.fill(band, signs, neighbours);
                    open_faces(cells, brick * BRICK, &mut out);
                    *table = edge_tables::table(cells);
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
