//! The field values around one brick, gathered from it and its 26 neighbours, so that cells
//! and edges crossing brick borders are handled with plain array indexing.

use glam::{IVec3, Vec3};

use super::band::{BRICK, Band};
use super::field_sampling::BrickValues;
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

    /// The values around the brick whose neighbours (by [`neighbour_slot`]) are `neighbours`.
    pub fn fill(&mut self, band: &Band, values: &BrickValues, neighbours: &[Option<usize>; 27]) {
        self.values.fill(f32::NAN);
        for (n, slot) in neighbours.iter().enumerate() {
            let Some(b) = *slot else { continue };
            let d = IVec3::new(n as i32 % 3, n as i32 / 3 % 3, n as i32 / 9) - 1;
            let lo = (d * BRICK).max(IVec3::splat(-1));
            let hi = (d * BRICK + BRICK - 1).min(IVec3::splat(BRICK + 1));
            // The neighbour's x range, as bits of its rows.
            let x0 = (lo.x - d.x * BRICK) as u32;
            let width = (hi.x - lo.x + 1) as usize;
            let take = (1u32 << width) - 1;
            let mask = &band.masks[b];
            for z in lo.z..=hi.z {
                let lz = (z - d.z * BRICK) as usize;
                let (word, plane) = (mask[lz], values.plane(mask, b, lz));
                for y in lo.y..=hi.y {
                    let first = x0 + (BRICK * (y - d.y * BRICK)) as u32;
                    let row = (word >> first) as u32 & take;
                    if row == 0 {
                        continue;
                    }
                    let rank = (word & ((1u64 << first) - 1)).count_ones() as usize;
                    let at = halo_index(IVec3::new(lo.x, y, z));
                    let out = &mut self.values[at..at + width];
                    if row == take {
                        out.copy_from_slice(&plane[rank..rank + width]);
                        continue;
                    }
                    let mut bits = row;
                    let mut k = rank;
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
