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
    /// Index of the brick at offset (dx, dy, dz) ∈ {−1, 0, 1}³, if it exists.
    pub neighbours: [Option<usize>; 27],
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
            neighbours: [None; 27],
        }
    }

    pub fn fill(&mut self, band: &Band, values: &BrickValues, brick: IVec3) {
        self.values.fill(f32::NAN);
        for (n, slot) in self.neighbours.iter_mut().enumerate() {
            let d = IVec3::new(n as i32 % 3, n as i32 / 3 % 3, n as i32 / 9) - 1;
            *slot = band.brick_index(brick + d);
            let Some(b) = *slot else { continue };
            let lo = (d * BRICK).max(IVec3::splat(-1));
            let hi = (d * BRICK + BRICK - 1).min(IVec3::splat(BRICK + 1));
            let mask = &band.masks[b];
            for z in lo.z..=hi.z {
                let lz = (z - d.z * BRICK) as usize;
                let (word, plane) = (mask[lz], values.plane(mask, b, lz));
                for y in lo.y..=hi.y {
                    for x in lo.x..=hi.x {
                        let bit = (x - d.x * BRICK + BRICK * (y - d.y * BRICK)) as u32;
                        // A full plane (inside the fluid's band, most of them) needs no count.
                        let rank = if word == u64::MAX {
                            bit as usize
                        } else if word >> bit & 1 == 1 {
                            (word & ((1u64 << bit) - 1)).count_ones() as usize
                        } else {
                            continue;
                        };
                        self.values[halo_index(IVec3::new(x, y, z))] = plane[rank];
                    }
                }
            }
        }
    }

    #[inline]
    pub fn at(&self, l: IVec3) -> f32 {
        self.values[halo_index(l)]
    }

    /// Whether all eight corners of the cell with lowest corner `l` are surface vertices.
    pub fn complete(&self, l: IVec3) -> bool {
        (0..8).all(|c| !self.at(l + offset(c)).is_nan())
    }

    pub fn corners(&self, l: IVec3) -> [f32; 8] {
        std::array::from_fn(|c| self.at(l + offset(c)))
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

/// Whether brick `brick` owns a cell (lowest corner in it) with an inside corner, given each
/// brick's [`BrickValues::inside_lows`]: only those bricks can own crossed cells and the
/// edges of their vertices; the rest (most of the band around a droplet) are skipped.
pub fn owns_inside_corner(band: &Band, lows: &[[u8; 3]], brick: IVec3) -> bool {
    (0..8).any(|c| {
        let d = offset(c);
        band.brick_index(brick + d).is_some_and(|n| {
            let low = lows[n];
            // The neighbour's inside vertices must reach its side facing this brick.
            (0..3).all(|a| {
                if d[a] == 1 {
                    low[a] == 0
                } else {
                    low[a] < BRICK as u8
                }
            })
        })
    })
}
