//! The narrow band of surface vertices (Sec. 4.1), stored sparsely.
//!
//! The paper keeps one integer per vertex of the whole grid; here the grid is cut into bricks
//! of 8×8×8 vertices and only bricks holding surface vertices exist (the coarse-cell indexing
//! of Wu et al. 2016), each with a bit per vertex. Memory follows the surface: a droplet far
//! from the fluid adds a brick or two, not a box of empty cells.
//!
//! Vertex `v` sits at `v * cell` in world coordinates, so the grid is the same in every frame.

use crate::error::Result;
use crate::recon::budget;
use glam::{IVec3, Vec3};
use rayon::prelude::*;
use rustc_hash::FxHashMap;

/// Vertices per brick side.
pub const BRICK: i32 = 8;
pub const BRICK_VERTICES: usize = 512;

/// Vertex coordinates must stay far from i32 overflow, also after adding halos.
const MAX_VERTEX_COORD: f64 = (1 << 29) as f64;

#[derive(Clone)]
pub struct Band {
    pub cell: f32,
    /// Brick coordinates, sorted by (z, y, x): the order of every per-brick output.
    pub bricks: Vec<IVec3>,
    /// Surface vertex bits per brick: bit `x + 8y` of word `z` (local coordinates).
    pub masks: Vec<[u64; 8]>,
    index: FxHashMap<IVec3, u32>,
}

/// Local index of a vertex inside its brick.
#[inline]
pub fn local_index(l: IVec3) -> usize {
    (l.x + BRICK * (l.y + BRICK * l.z)) as usize
}

/// The local coordinates of the vertex with [`local_index`] `i`.
#[inline]
pub fn local_vertex(i: usize) -> IVec3 {
    let i = i as i32;
    IVec3::new(i % BRICK, i / BRICK % BRICK, i / (BRICK * BRICK))
}

#[inline]
pub fn brick_of(v: IVec3) -> IVec3 {
    IVec3::new(v.x >> 3, v.y >> 3, v.z >> 3)
}

impl Band {
    /// Marks every vertex in the box of half-width `half_width` around each surface particle.
    #[cfg(test)]
    pub fn around(surface: &[Vec3], cell: f32, half_width: f32) -> Result<Band> {
        Band::around_within(surface, cell, &vec![half_width; surface.len()], |_| Ok(()))
    }

    /// [`Band::around`] with a half-width per particle, calling `budget` with the number of
    /// (brick, particle) pairs that building it takes (at most 16 bytes each, twice while they
    /// are gathered) before allocating them: a cell far smaller than the band makes billions.
    pub fn around_within(
        surface: &[Vec3],
        cell: f32,
        half_widths: &[f32],
        budget: impl FnOnce(u64) -> Result<()>,
    ) -> Result<Band> {
        let boxes: Vec<(IVec3, IVec3)> = surface
            .par_iter()
            .zip(half_widths)
            .map(|(&p, &w)| vertex_box(p, cell, w))
            .collect::<Result<_>>()?;
        let bricks_of = |&(lo, hi): &(IVec3, IVec3)| -> u64 {
            let n = brick_of(hi) - brick_of(lo) + 1;
            n.to_array()
                .iter()
                .fold(1u64, |a, &k| a.saturating_mul(k.max(0) as u64))
        };
        let count = boxes
            .par_iter()
            .map(bricks_of)
            .reduce(|| 0, u64::saturating_add);
        budget(count)?;
        let len = usize::try_from(count).unwrap_or(usize::MAX);
        if len == 0 {
            return Ok(Band::from_masks(cell, Vec::new(), Vec::new()));
        }
        // Brick coordinates from the lowest brick, in as few bits as the band's extent needs:
        // most bands sort 8-byte keys instead of 16-byte ones.
        let lo = boxes
            .par_iter()
            .map(|b| brick_of(b.0))
            .reduce(|| IVec3::MAX, IVec3::min);
        let hi = boxes
            .par_iter()
            .map(|b| brick_of(b.1))
            .reduce(|| IVec3::MIN, IVec3::max);
        let span = (hi.as_i64vec3() - lo.as_i64vec3())
            .to_array()
            .map(|n| n as u64);
        let layout = Layout::new([span[0], span[1], span[2], surface.len() as u64 - 1]);
        if layout.bits <= u64::BITS {
            band_of_pairs::<u64>(&boxes, cell, lo, &layout, len)
        } else {
            band_of_pairs::<u128>(&boxes, cell, lo, &layout, len)
        }
    }

    /// Every vertex of the box `[lo, hi]` widened by `margin`: the full grid, for engines and
    /// checks that process the whole volume.
    pub fn full(lo: Vec3, hi: Vec3, cell: f32, margin: f32) -> Result<Band> {
        let (vlo, vhi) = Band::full_extent(lo, hi, cell, margin)?;
        let (a, b) = (brick_of(vlo), brick_of(vhi));
        let n = (b - a + 1)
            .to_array()
            .iter()
            .fold(1u64, |n, &k| n.saturating_mul(k.max(0) as u64));
        let n = usize::try_from(n).unwrap_or(usize::MAX);
        let what = || format!("the {n} bricks of the full grid");
        let mut bricks = budget::try_vec(n, what)?;
        let mut masks = budget::try_vec(n, what)?;
        for z in a.z..=b.z {
            for y in a.y..=b.y {
                for x in a.x..=b.x {
                    let brick = IVec3::new(x, y, z);
                    let mut mask = [0; 8];
                    mark_box(&mut mask, brick, vlo, vhi);
                    bricks.push(brick);
                    masks.push(mask);
                }
            }
        }
        Ok(Band::from_masks(cell, bricks, masks))
    }

    /// First and last grid vertex of [`Band::full`]'s box, without building it.
    pub fn full_extent(lo: Vec3, hi: Vec3, cell: f32, margin: f32) -> Result<(IVec3, IVec3)> {
        let (vlo, _) = vertex_box(lo, cell, margin)?;
        let (_, vhi) = vertex_box(hi, cell, margin)?;
        Ok((vlo, vhi))
    }

    /// A band of exactly `vertices`, which must be sorted by (z, y, x).
    pub fn from_vertices(vertices: &[IVec3], cell: f32) -> Band {
        let mut bricks: Vec<IVec3> = vertices.iter().map(|&v| brick_of(v)).collect();
        bricks.sort_unstable_by_key(|b| (b.z, b.y, b.x));
        bricks.dedup();
        let mut band = Band::from_masks(cell, bricks.clone(), vec![[0; 8]; bricks.len()]);
        for &v in vertices {
            let b = band.index[&brick_of(v)] as usize;
            let l = v - brick_of(v) * BRICK;
            band.masks[b][l.z as usize] |= 1 << (l.x + BRICK * l.y);
        }
        band
    }

    /// A band of `bricks` (sorted by (z, y, x)) with their vertex `masks`.
    pub fn from_masks(cell: f32, bricks: Vec<IVec3>, masks: Vec<[u64; 8]>) -> Band {
        let index = bricks
            .iter()
            .enumerate()
            .map(|(i, &b)| (b, i as u32))
            .collect();
        Band {
            cell,
            bricks,
            masks,
            index,
        }
    }

    pub fn brick_index(&self, brick: IVec3) -> Option<usize> {
        self.index.get(&brick).map(|&i| i as usize)
    }

    pub fn surface_vertices(&self) -> usize {
        self.masks
            .iter()
            .flatten()
            .map(|w| w.count_ones() as usize)
            .sum()
    }

    pub fn heap_bytes(&self) -> usize {
        self.bricks.capacity() * size_of::<IVec3>()
            + self.masks.capacity() * size_of::<[u64; 8]>()
            + self.index.capacity() * (size_of::<(IVec3, u32)>() + 1)
    }
}

/// Where the fields of a packed (brick, particle) pair sit: brick x, y, z (from the lowest
/// brick) and the particle index, so that keys sort as (z, y, x, particle).
struct Layout {
    shifts: [u32; 4],
    masks: [u64; 4],
    bits: u32,
}

impl Layout {
    /// The layout of fields up to `max` each.
    fn new(max: [u64; 4]) -> Layout {
        let widths = max.map(|m| u64::BITS - m.leading_zeros());
        let mut shifts = [0; 4];
        let mut bits = 0;
        for field in [3, 0, 1, 2] {
            shifts[field] = bits;
            bits += widths[field];
        }
        let masks = widths.map(|w| u64::MAX.checked_shr(u64::BITS - w).unwrap_or(0));
        Layout {
            shifts,
            masks,
            bits,
        }
    }
}

/// An integer holding a (brick, particle) pair by a [`Layout`].
trait PairKey: Copy + Ord + Send + Sync {
    fn pack(fields: [u64; 4], layout: &Layout) -> Self;
    fn field(self, field: usize, layout: &Layout) -> u64;
}

macro_rules! pair_key {
    ($t:ty) => {
        impl PairKey for $t {
            fn pack(fields: [u64; 4], layout: &Layout) -> $t {
                (0..4).fold(0, |key, f| {
                    key | <$t>::from(fields[f])
                        .checked_shl(layout.shifts[f])
                        .unwrap_or(0)
                })
            }

            fn field(self, field: usize, layout: &Layout) -> u64 {
                self.checked_shr(layout.shifts[field]).unwrap_or(0) as u64 & layout.masks[field]
            }
        }
    };
}
pair_key!(u64);
pair_key!(u128);

/// The band of the particles' vertex boxes `boxes`, from their `len` (brick, particle) pairs
/// packed as `K` by `layout`, bricks counted from `lo`.
fn band_of_pairs<K: PairKey>(
    boxes: &[(IVec3, IVec3)],
    cell: f32,
    lo: IVec3,
    layout: &Layout,
    len: usize,
) -> Result<Band> {
    // One pair per brick a particle's box touches, grouped by brick.
    let mut pairs: Vec<K> =
        budget::try_vec(len, || format!("the band's {len} (brick, particle) pairs"))?;
    pairs.par_extend(boxes.par_iter().enumerate().flat_map_iter(|(i, &(a, b))| {
        let (a, b) = (brick_of(a) - lo, brick_of(b) - lo);
        (a.z..=b.z).flat_map(move |z| {
            (a.y..=b.y).flat_map(move |y| {
                (a.x..=b.x).map(move |x| K::pack([x as u64, y as u64, z as u64, i as u64], layout))
            })
        })
    }));
    pairs.par_sort_unstable();
    let brick = |k: K| [0, 1, 2].map(|f| k.field(f, layout) as i32);
    let (bricks, masks) = pairs
        .par_chunk_by(|&a, &b| brick(a) == brick(b))
        .map(|group| {
            let brick = lo + IVec3::from_array(brick(group[0]));
            let mut mask = [0u64; 8];
            for &k in group.iter() {
                let (lo, hi) = boxes[k.field(3, layout) as usize];
                mark_box(&mut mask, brick, lo, hi);
            }
            (brick, mask)
        })
        .unzip();
    Ok(Band::from_masks(cell, bricks, masks))
}

/// Grid vertices in the box of half-width `w` around `p`.
fn vertex_box(p: Vec3, cell: f32, w: f32) -> Result<(IVec3, IVec3)> {
    let (c, w) = (f64::from(cell), f64::from(w));
    let lo = (p.as_dvec3() - w) / c;
    let hi = (p.as_dvec3() + w) / c;
    if lo.abs().max_element() >= MAX_VERTEX_COORD || hi.abs().max_element() >= MAX_VERTEX_COORD {
        // The box's far corner, not the particle, is what leaves the grid (a cell of 1e30
        // put the particle 2.929e-40 cells from the origin, and its box of half-width w out).
        bail_limit!(
            "the band around the particle at {p} reaches {:.3e} cells of {} from the origin, \
             beyond the grid's {:.3e}",
            lo.abs().max(hi.abs()).max_element(),
            crate::error::figure(cell),
            MAX_VERTEX_COORD
        );
    }
    Ok((lo.ceil().as_ivec3(), hi.floor().as_ivec3()))
}

/// Sets the bits of the vertices of `[lo, hi]` that fall inside `brick`.
fn mark_box(mask: &mut [u64; 8], brick: IVec3, lo: IVec3, hi: IVec3) {
    let base = brick * BRICK;
    let a = (lo - base).max(IVec3::ZERO);
    let b = (hi - base).min(IVec3::splat(BRICK - 1));
    if a.cmpgt(b).any() {
        return;
    }
    let row = ((1u64 << (b.x - a.x + 1)) - 1) << a.x;
    let mut plane = 0u64;
    for y in a.y..=b.y {
        plane |= row << (BRICK * y);
    }
    for word in &mut mask[a.z as usize..=b.z as usize] {
        *word |= plane;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn band_marks_the_box_around_each_particle() {
        let band = Band::around(&[Vec3::new(0.05, 0.05, 0.05)], 0.1, 0.2).unwrap();
        // Vertices −1..=2 on each axis: 4³, spread over the bricks at −1 and 0.
        assert_eq!(band.surface_vertices(), 64);
        assert_eq!(band.bricks.len(), 8);
    }

    #[test]
    fn wide_bands_sort_wide_keys_to_the_same_band() {
        // 10⁸ cells apart: the pairs need more than 64 bits, so they sort as u128.
        let near: Vec<Vec3> = (0..50).map(|i| Vec3::splat(i as f32 * 0.013)).collect();
        let far: Vec<Vec3> = near.iter().map(|&p| p + Vec3::splat(1.0e6)).collect();
        let both: Vec<Vec3> = near.iter().chain(&far).copied().collect();
        let [a, b, ab] = [&near, &far, &both].map(|p| Band::around(p, 0.01, 0.02).unwrap());
        let span = ab.bricks.last().unwrap() - ab.bricks[0];
        let layout = Layout::new([span.x, span.y, span.z, 99].map(|n| n as u64));
        assert!(layout.bits > u64::BITS, "{}", layout.bits);
        assert_eq!(ab.bricks, [a.bricks, b.bricks].concat());
        assert_eq!(ab.masks, [a.masks, b.masks].concat());
    }

    #[test]
    fn pair_keys_keep_their_fields() {
        let layout = Layout::new([5, 0, 1000, 70_000]);
        // 3 bits for x, none for y (always 0), 10 for z, 17 for the particle.
        assert_eq!(layout.bits, 30);
        let key = u64::pack([4, 0, 999, 65_432], &layout);
        assert_eq!(
            [0, 1, 2, 3].map(|f| key.field(f, &layout)),
            [4, 0, 999, 65_432]
        );
        let wide = u128::pack([4, 0, 999, 65_432], &layout);
        assert_eq!(wide, u128::from(key));
    }

    #[test]
    fn far_particle_adds_bricks_not_volume() {
        let near: Vec<Vec3> = (0..100).map(|i| Vec3::splat(i as f32 * 0.01)).collect();
        let mut far = near.clone();
        far.push(Vec3::splat(1.0e3));
        let a = Band::around(&near, 0.01, 0.02).unwrap();
        let b = Band::around(&far, 0.01, 0.02).unwrap();
        assert!(b.bricks.len() <= a.bricks.len() + 8);
    }
}
