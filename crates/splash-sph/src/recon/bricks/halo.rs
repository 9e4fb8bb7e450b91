//! The field values around one brick, gathered from it and its 26 neighbours, so that cells
//! and edges crossing brick borders are handled with plain array indexing.

use glam::{IVec3, Vec3};

use super::band::{BRICK, Band};
use super::brick_values::BrickValues;
use crate::mesh::marching_cubes::corner_offset;

/// Local coordinates −1..=9: a brick, its +1 neighbours for cells and edges that leave it, and
/// one more layer each way for central differences.
const SIDE: i32 = BRICK + 3;

/// Field values around one brick.
pub struct Halo {
    values: Vec<f32>,
}

impl Default for Halo {
    fn default() -> Halo {
        Halo::new()
    }
}

impl Halo {
    pub fn new() -> Halo {
        Halo {
            values: vec![f32::NAN; (SIDE * SIDE * SIDE) as usize],
        }
    }

    /// The values in the box `lo..=hi` (local coordinates −1..=9) around the brick whose
    /// neighbours (by [`neighbour_slot`]) are `neighbours`; the rest of the halo keeps what an
    /// earlier brick left there.
    pub fn fill(
        &mut self,
        band: &Band,
        values: &BrickValues,
        neighbours: &[Option<usize>; 27],
        lo: IVec3,
        hi: IVec3,
    ) {
        let width = (hi.x - lo.x + 1) as usize;
        for z in lo.z..=hi.z {
            let (dz, lz) = split(z);
            for y in lo.y..=hi.y {
                let (dy, ly) = split(y);
                let at = halo_index(IVec3::new(lo.x, y, z));
                let row = &mut self.values[at..at + width];
                row.fill(f32::NAN);
                for dx in -1..=1 {
                    // The part of the row in the neighbour at dx.
                    let (xa, xb) = (lo.x.max(dx * BRICK), hi.x.min(dx * BRICK + BRICK - 1));
                    let Some(b) = neighbours[neighbour_slot(IVec3::new(dx, dy, dz))] else {
                        continue;
                    };
                    if xa > xb {
                        continue;
                    }
                    let mask = &band.masks[b];
                    let word = mask[lz as usize];
                    let first = (xa - dx * BRICK + BRICK * ly) as u32;
                    let take = (1u32 << (xb - xa + 1)) - 1;
                    let bits = (word >> first) as u32 & take;
                    if bits == 0 {
                        continue;
                    }
                    let plane = values.plane(mask, b, lz as usize);
                    let rank = (word & ((1u64 << first) - 1)).count_ones() as usize;
                    let out = &mut row[(xa - lo.x) as usize..=(xb - lo.x) as usize];
                    if bits == take {
                        out.copy_from_slice(&plane[rank..rank + out.len()]);
                        continue;
                    }
                    let (mut bits, mut k) = (bits, rank);
                    while bits != 0 {
                        out[bits.trailing_zeros() as usize] = plane[k];
                        k += 1;
                        bits &= bits - 1;
                    }
                }
            }
        }
    }

    #[inline]
    pub fn at(&self, l: IVec3) -> f32 {
        self.values[halo_index(l)]
    }

    /// Central differences of the field, one-sided where a neighbour is outside the band.
    pub fn gradient(&self, l: IVec3, cell: f32) -> Vec3 {
        let v = self.at(l);
        Vec3::from_array(std::array::from_fn(|a| {
            let e = IVec3::AXES[a];
            let (m, p) = (self.at(l - e), self.at(l + e));
            match (m.is_nan(), p.is_nan()) {
                (false, false) => (p - m) / (2.0 * cell),
                (true, false) => (p - v) / cell,
                (false, true) => (v - m) / cell,
                (true, true) => 0.0,
            }
        }))
    }
}

/// The brick offset (−1, 0 or 1) and local coordinate of halo coordinate `h` on one axis.
fn split(h: i32) -> (i32, i32) {
    let d = h.div_euclid(BRICK);
    (d, h - d * BRICK)
}

fn halo_index(l: IVec3) -> usize {
    let s = l + 1;
    (s.x + SIDE * (s.y + SIDE * s.z)) as usize
}

pub fn offset(c: usize) -> IVec3 {
    IVec3::from_array(corner_offset(c).map(|o| o as i32))
}

pub fn neighbour_slot(d: IVec3) -> usize {
    let s = d + 1;
    (s.x + 3 * s.y + 9 * s.z) as usize
}
