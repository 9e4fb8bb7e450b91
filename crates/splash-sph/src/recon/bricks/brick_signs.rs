//! The signs of the band's field values as bit planes laid out like the band's masks: which
//! vertices hold a value and which lie inside (negative). The triangulation's tests (Sec. 4.2:
//! a cell's eight corners in the band, its case, an edge's sign change) need only these, so
//! they run on rows of vertices at once instead of on the values.

use rayon::prelude::*;

use super::band::Band;
use super::brick_values::BrickValues;
use super::halo::{neighbour_slot, offset};

/// Set in a brick's slot when some vertex of its mask has a NaN value: the plane after its
/// inside plane then holds the vertices with a value.
const HOLES: u32 = 1 << 31;
const NONE: [u64; 8] = [0; 8];
/// Bricks per parallel task.
const CHUNK: usize = 1024;

/// Sign planes of a band's bricks; only bricks with an inside vertex (or a NaN value) keep a
/// plane, so a band of mostly empty bricks around droplets costs 4 bytes a brick.
#[derive(Clone)]
pub struct Signs {
    /// Per brick: 0 when it has no inside vertex and every vertex of its mask has a value;
    /// else 1 + the index of its inside plane, with [`HOLES`] maybe set.
    slots: Vec<u32>,
    planes: Vec<[u64; 8]>,
}

impl Signs {
    pub fn of(band: &Band, values: &BrickValues) -> Signs {
        let parts: Vec<(Vec<u32>, Vec<[u64; 8]>)> = band
            .masks
            .par_chunks(CHUNK)
            .enumerate()
            .map(|(c, masks)| {
                let mut slots = Vec::with_capacity(masks.len());
                let mut planes = Vec::new();
                for (i, mask) in masks.iter().enumerate() {
                    let (inside, present) = brick_signs(mask, values.brick(c * CHUNK + i));
                    if inside == NONE && present == *mask {
                        slots.push(0);
                        continue;
                    }
                    let mut slot = planes.len() as u32 + 1;
                    planes.push(inside);
                    if present != *mask {
                        slot |= HOLES;
                        planes.push(present);
                    }
                    slots.push(slot);
                }
                (slots, planes)
            })
            .collect();
        let mut slots = Vec::with_capacity(band.masks.len());
        let mut planes = Vec::with_capacity(parts.iter().map(|p| p.1.len()).sum());
        for (s, p) in parts {
            let before = planes.len() as u32;
            slots.extend(s.into_iter().map(|s| if s == 0 { 0 } else { s + before }));
            planes.extend(p);
        }
        Signs { slots, planes }
    }

    /// The (present, inside) planes of brick `b`, whose band mask is `mask`.
    #[inline]
    pub fn planes<'a>(&'a self, mask: &'a [u64; 8], b: usize) -> (&'a [u64; 8], &'a [u64; 8]) {
        let slot = self.slots[b];
        if slot == 0 {
            return (mask, &NONE);
        }
        let i = (slot & !HOLES) as usize - 1;
        let present = if slot & HOLES == 0 {
            mask
        } else {
            &self.planes[i + 1]
        };
        (present, &self.planes[i])
    }

    /// The inside plane of brick `b`.
    #[inline]
    pub fn inside(&self, b: usize) -> &[u64; 8] {
        match self.slots[b] {
            0 => &NONE,
            slot => &self.planes[(slot & !HOLES) as usize - 1],
        }
    }

    /// Whether the brick whose neighbours (by [`neighbour_slot`]) are `neighbours` owns a
    /// cell (lowest corner in it) with an inside corner: only those bricks can own crossed
    /// cells and the edges of their vertices; the rest (most of the band around a droplet)
    /// are skipped.
    pub fn owns_inside_corner(&self, neighbours: &[Option<usize>; 27]) -> bool {
        (0..8).any(|c| {
            let d = offset(c);
            neighbours[neighbour_slot(d)].is_some_and(|n| {
                // The corners in a neighbour lie on its side facing this brick.
                let plane = if d.x == 1 {
                    0x0101_0101_0101_0101
                } else {
                    u64::MAX
                };
                let plane = if d.y == 1 { plane & 0xff } else { plane };
                let inside = self.inside(n);
                let planes = if d.z == 1 { &inside[..1] } else { &inside[..] };
                planes.iter().any(|w| w & plane != 0)
            })
        })
    }

    pub fn heap_bytes(&self) -> usize {
        self.slots.capacity() * size_of::<u32>() + self.planes.capacity() * size_of::<[u64; 8]>()
    }
}

/// The inside and present planes of one brick from its packed values.
fn brick_signs(mask: &[u64; 8], values: &[f32]) -> ([u64; 8], [u64; 8]) {
    let (mut inside, mut present) = (NONE, NONE);
    let mut k = 0;
    for (z, &word) in mask.iter().enumerate() {
        let (mut i, mut p) = (0u64, 0u64);
        if word == u64::MAX {
            // A full plane's values are in bit order, one per bit.
            for (bit, &v) in values[k..k + 64].iter().enumerate() {
                i |= u64::from(v < 0.0) << bit;
                p |= u64::from(!v.is_nan()) << bit;
            }
            k += 64;
        } else {
            let mut bits = word;
            while bits != 0 {
                let bit = bits.trailing_zeros();
                let v = values[k];
                i |= u64::from(v < 0.0) << bit;
                p |= u64::from(!v.is_nan()) << bit;
                k += 1;
                bits &= bits - 1;
            }
        }
        (inside[z], present[z]) = (i, p);
    }
    (inside, present)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recon::bricks::band::BRICK_VERTICES;
    use glam::Vec3;

    #[test]
    fn planes_follow_the_values_signs_and_holes() {
        let band = Band::full(Vec3::ZERO, Vec3::splat(1.25), 0.1, 0.0).unwrap();
        assert!(band.bricks.len() > 2);
        // Brick 0 all outside, brick 1 with inside vertices, brick 2 with a NaN too.
        let values = BrickValues::sample(
            &band,
            || (),
            |_, b| {
                let mut v = [1.0f32; BRICK_VERTICES];
                if b >= 1 {
                    v[3] = -1.0;
                    v[200] = -0.5;
                }
                if b == 2 {
                    v[7] = f32::NAN;
                }
                v
            },
        )
        .unwrap();
        let signs = Signs::of(&band, &values);
        for b in 0..band.bricks.len() {
            let mask = &band.masks[b];
            let (present, inside) = signs.planes(mask, b);
            assert_eq!(inside, signs.inside(b));
            for local in 0..BRICK_VERTICES {
                let (w, bit) = (local / 64, local % 64);
                let v = values.get(mask, b, local);
                assert_eq!(
                    present[w] >> bit & 1 == 1,
                    !v.is_nan(),
                    "brick {b}, {local}"
                );
                assert_eq!(inside[w] >> bit & 1 == 1, v < 0.0, "brick {b}, {local}");
            }
        }
        assert_eq!(signs.slots[0], 0);
        assert_eq!(signs.slots[2] & HOLES, HOLES);
    }
}
