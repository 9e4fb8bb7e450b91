//! Cells numbered by one 32-bit key (the clearance's vertex grid; the signed-distance bins
//! number their bricks so): sorting by cell takes a radix sort of few passes, or entries of
//! one word with an index.

use glam::{IVec3, Vec3};

use super::cell_of;

/// Cells numbered from the lowest a set of points meets (a mesh's vertices), their three
/// coordinates packed into one 32-bit key as few bits wide as the points' span needs: a radix
/// sort then takes three or four passes, and a lookup hashes one word.
#[derive(Debug, Clone, Copy)]
pub(crate) struct CellKeys {
    low: IVec3,
    high: IVec3,
    /// Where the y and z coordinates start.
    y: u32,
    z: u32,
}

impl CellKeys {
    /// The numbering of the cells from `low` to `high` in at most `bits` bits, if they fit.
    fn spanning(low: IVec3, high: IVec3, bits: u32) -> Option<CellKeys> {
        let high = high.max(low);
        let span = (high.as_i64vec3() - low.as_i64vec3()).max(glam::I64Vec3::ZERO);
        let widths = span.to_array().map(|s| 64 - (s as u64).leading_zeros());
        (widths.iter().sum::<u32>() <= bits).then_some(CellKeys {
            low,
            high,
            y: widths[0],
            z: widths[0] + widths[1],
        })
    }

    /// The numbering of cells at least `cell` wide over the box `bounds` (around a mesh's
    /// vertices), and their width: `cell`, doubled until the span fits in 32 bits (a box
    /// thousands of cells across in every direction gets wider cells, each holding more).
    pub(crate) fn fitting(bounds: (Vec3, Vec3), cell: f32) -> (CellKeys, f32) {
        CellKeys::fit(bounds, cell, 0, 32)
    }

    /// The numbering of the bricks of 4³ cells (a cell c in brick c >> 2) over the box
    /// `bounds`, in 26 bits so that a cell's place in its brick fits beside, and the cells'
    /// width, doubled as [`fitting`](Self::fitting) doubles it.
    pub(crate) fn fitting_bricks(bounds: (Vec3, Vec3), cell: f32) -> (CellKeys, f32) {
        CellKeys::fit(bounds, cell, 2, 26)
    }

    /// The numbering of the groups of cells `cell` wide (a cell c in group c >> `shift`) over
    /// the box `(lo, hi)` in `bits` bits, `cell` doubled until they fit.
    fn fit((lo, hi): (Vec3, Vec3), mut cell: f32, shift: i32, bits: u32) -> (CellKeys, f32) {
        loop {
            // The floor is monotone: the cells of the lowest and highest coordinates.
            let (low, high) = (cell_of(lo, cell) >> shift, cell_of(hi, cell) >> shift);
            match CellKeys::spanning(low, high, bits) {
                Some(keys) => return (keys, cell),
                None => cell *= 2.0,
            }
        }
    }

    /// The key of cell `c`, which lies within the mesh's cells.
    pub(crate) fn packed(&self, c: IVec3) -> u32 {
        let c = (c - self.low).as_uvec3();
        // A span of 32 bits in x alone leaves nothing to shift in.
        c.z.checked_shl(self.z).unwrap_or(0) | c.y.checked_shl(self.y).unwrap_or(0) | c.x
    }

    /// The key of cell `c`, or None when it lies beyond the mesh's cells (and so is empty).
    pub(crate) fn key(&self, c: IVec3) -> Option<u32> {
        (c.cmpge(self.low).all() && c.cmple(self.high).all()).then(|| self.packed(c))
    }
}
