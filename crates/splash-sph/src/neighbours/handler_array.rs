//! The handler array of Sec. 4.1: particles sorted by the Z-order (Morton) id of their lookup
//! cell (eqs. 6–8), stored contiguously, with the start of every non-empty cell.
//!
//! Unlike the paper's `startIndices`, which holds one integer per cell of the bounding box, the
//! cell starts are kept for non-empty cells only, found through a hash map over the Morton
//! blocks of 4³ cells that hold particles, so a droplet far from the fluid costs one entry
//! instead of a box full of empty cells, and a gather over a few hundred cells costs a few
//! dozen hash lookups (one per cell was half of every gather's time).

use crate::error::Result;
use glam::{DVec3, IVec3, Vec3};
use rayon::prelude::*;
use rustc_hash::FxHashMap;

use super::counting_sort::sort_by_bucket_into;

/// Morton codes interleave 21 bits per axis into a u64.
const AXIS_BITS: u32 = 21;

pub struct HandlerArray {
    cell_size: f32,
    /// Lowest occupied cell; Morton codes are taken relative to it.
    origin: IVec3,
    /// Highest occupied cell on each axis: with `origin`, the box that cell loops stay in.
    last: IVec3,
    /// Particle positions in handler order (sorted by cell id).
    pub positions: Vec<Vec3>,
    /// Per-particle attribute channels, each in handler order, for fields whose kernels carry
    /// per-particle data (the density field's volumes m/ρ in channel 0; the anisotropic
    /// field's matrices); empty for the others, whose gathers then copy positions only.
    pub channels: Vec<Vec<f32>>,
    /// Morton block (cell id >> 6) → its non-empty cells.
    blocks: FxHashMap<u64, CellBlock>,
    /// Where each non-empty cell's particles start, in cell id order, then the particle count.
    starts: Vec<u32>,
}

/// The non-empty cells of a Morton block of 4³ cells: a bit per cell (by the low 6 bits of its
/// id), and the index in `starts` of the first.
#[derive(Clone, Copy)]
struct CellBlock {
    occupied: u64,
    first: u32,
}

impl CellBlock {
    /// The index in `starts` of the cell with low id bits `bit`, if it holds particles.
    #[inline]
    fn cell(&self, bit: u64) -> Option<usize> {
        (self.occupied >> bit & 1 == 1)
            .then(|| self.first as usize + (self.occupied & ((1 << bit) - 1)).count_ones() as usize)
    }
}

impl HandlerArray {
    pub fn new(particles: &[Vec3], cell_size: f32) -> Result<HandlerArray> {
        Ok(Self::sorted(particles, cell_size)?.0)
    }

    /// A handler array over `particles` with per-particle `channels` given in the order of
    /// `particles`, reordered with them into handler order.
    pub fn with_channels(
        particles: &[Vec3],
        cell_size: f32,
        channels: Vec<Vec<f32>>,
    ) -> Result<HandlerArray> {
        let (mut handlers, order) = Self::sorted(particles, cell_size)?;
        handlers.channels = channels
            .into_iter()
            .map(|c| {
                assert_eq!(c.len(), particles.len(), "one value per particle");
                (0..order.len())
                    .into_par_iter()
                    .map(|k| c[order.get(k).1 as usize])
                    .collect()
            })
            .collect();
        Ok(handlers)
    }

    /// The handler array and its handlers (cell id, index into `particles`), in handler order.
    fn sorted(particles: &[Vec3], cell_size: f32) -> Result<(HandlerArray, Handlers)> {
        if particles.len() >= u32::MAX as usize {
            bail_limit!(
                "{} particles are more than one frame can hold",
                particles.len()
            );
        }
        let cell_of = |p: Vec3| cell_of(p, cell_size);
        let (lo, hi) = particles
            .par_iter()
            .map(|&p| (cell_of(p), cell_of(p)))
            .reduce(
                || (IVec3::MAX, IVec3::MIN),
                |a, b| (a.0.min(b.0), a.1.max(b.1)),
            );
        let (origin, last) = if particles.is_empty() {
            (IVec3::ZERO, IVec3::splat(-1))
        } else {
            (lo, hi)
        };
        let span = (hi - origin).max_element() as i64;
        if !particles.is_empty() && span >= 1 << AXIS_BITS {
            // Measured in f64 from the coordinates: the cells of f32 division saturate at
            // i32's range (2147483646 cells said nothing about the particles).
            let (lo, hi) = particles.iter().fold(
                (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
                |(lo, hi), p| (lo.min(p.as_dvec3()), hi.max(p.as_dvec3())),
            );
            let extent = (hi - lo).max_element();
            bail_limit!(
                "the particles span {} along one axis, {:.3e} lookup cells of {}; at most {} \
                 fit (a particle has escaped far from the fluid?)",
                crate::error::figure(extent as f32),
                extent / f64::from(cell_size),
                crate::error::figure(cell_size),
                1u64 << AXIS_BITS
            );
        }
        let id = |p: Vec3| morton(cell_of(p) - origin);
        let handlers = Handlers::sorted(particles, id, morton(last - origin));
        let positions = (0..handlers.len())
            .into_par_iter()
            .map(|k| particles[handlers.get(k).1 as usize])
            .collect();
        // The cells of a block follow each other in id order: one table entry per block.
        let mut blocks = FxHashMap::<u64, CellBlock>::default();
        let mut block: Option<(u64, CellBlock)> = None;
        let mut starts = Vec::new();
        let mut previous = None;
        for k in 0..handlers.len() {
            let id = handlers.get(k).0;
            if previous == Some(id) {
                continue;
            }
            previous = Some(id);
            match &mut block {
                Some((b, cells)) if *b == id >> 6 => cells.occupied |= 1 << (id & 63),
                _ => {
                    blocks.extend(block);
                    let cells = CellBlock {
                        occupied: 1 << (id & 63),
                        first: starts.len() as u32,
                    };
                    block = Some((id >> 6, cells));
                }
            }
            starts.push(k as u32);
        }
        blocks.extend(block);
        starts.push(handlers.len() as u32);
        let handlers_array = HandlerArray {
            cell_size,
            origin,
            last,
            positions,
            channels: Vec::new(),
            blocks,
            starts,
        };
        Ok((handlers_array, handlers))
    }

    pub fn cell_size(&self) -> f32 {
        self.cell_size
    }

    pub fn cell_of(&self, p: Vec3) -> IVec3 {
        cell_of(p, self.cell_size)
    }

    /// The handler-order range of one cell's particles.
    #[cfg(test)]
    fn cell_range(&self, cell: IVec3) -> std::ops::Range<usize> {
        let rel = cell - self.origin;
        if rel.min_element() < 0 || rel.max_element() >= 1 << AXIS_BITS {
            return 0..0;
        }
        let id = morton(rel);
        let block = self.blocks.get(&(id >> 6));
        self.range_in(block, id)
    }

    #[inline]
    fn range_in(&self, block: Option<&CellBlock>, id: u64) -> std::ops::Range<usize> {
        match block.and_then(|b| b.cell(id & 63)) {
            Some(k) => self.starts[k] as usize..self.starts[k + 1] as usize,
            None => 0..0,
        }
    }

    /// The particles of one cell, in handler order.
    #[cfg(test)]
    fn cell(&self, cell: IVec3) -> &[Vec3] {
        &self.positions[self.cell_range(cell)]
    }

    /// Calls `f` with the handler-order range of every non-empty cell overlapping `[lo, hi]`.
    pub fn for_each_in_box(&self, lo: Vec3, hi: Vec3, f: impl FnMut(std::ops::Range<usize>)) {
        self.for_each_in_cells(self.cell_of(lo), self.cell_of(hi), f);
    }

    /// Calls `f` with the handler-order range of every non-empty cell from `a` to `b`, in
    /// (z, y, x) order.
    pub fn for_each_in_cells(&self, a: IVec3, b: IVec3, mut f: impl FnMut(std::ops::Range<usize>)) {
        let (a, b) = self.occupied_part(a, b);
        if a.cmpgt(b).any() {
            return;
        }
        let (a, b) = (a - self.origin, b - self.origin);
        // Each Morton block of the box looked up once, into a small table when it fits.
        let (ba, bb) = (a >> 2i32, b >> 2i32);
        let dims = bb - ba + 1;
        let mut table = [None; 64];
        let mut looked = 0u64;
        let small = dims.x * dims.y * dims.z <= 64;
        let mut last = (u64::MAX, None);
        for z in a.z..=b.z {
            for y in a.y..=b.y {
                for x in a.x..=b.x {
                    let rel = IVec3::new(x, y, z);
                    let id = morton(rel);
                    let key = id >> 6;
                    let block = if small {
                        let d = (rel >> 2i32) - ba;
                        let slot = (d.x + dims.x * (d.y + dims.y * d.z)) as usize;
                        if looked >> slot & 1 == 0 {
                            table[slot] = self.blocks.get(&key).copied();
                            looked |= 1 << slot;
                        }
                        table[slot]
                    } else {
                        if last.0 != key {
                            last = (key, self.blocks.get(&key).copied());
                        }
                        last.1
                    };
                    let range = self.range_in(block.as_ref(), id);
                    if !range.is_empty() {
                        f(range);
                    }
                }
            }
        }
    }

    /// Whether the Morton blocks of 4³ cells that overlap `[lo, hi]` hold more than `limit`
    /// particles (whole blocks are counted: an upper bound of the particles in the box).
    pub fn more_near_than(&self, lo: Vec3, hi: Vec3, limit: usize) -> bool {
        let (a, b) = self.occupied_part(self.cell_of(lo), self.cell_of(hi));
        if a.cmpgt(b).any() {
            return false;
        }
        let (a, b) = ((a - self.origin) >> 2i32, (b - self.origin) >> 2i32);
        let mut count = 0;
        for z in a.z..=b.z {
            for y in a.y..=b.y {
                for x in a.x..=b.x {
                    if let Some(block) = self.blocks.get(&morton(IVec3::new(x, y, z))) {
                        let first = block.first as usize;
                        let end = first + block.occupied.count_ones() as usize;
                        count += (self.starts[end] - self.starts[first]) as usize;
                        if count > limit {
                            return true;
                        }
                    }
                }
            }
        }
        false
    }

    /// The part of the box of cells `[a, b]` that holds particles (empty when `a > b` on an
    /// axis). A query box can reach far beyond the particles, up to i32's saturated limits for
    /// cells far larger than the lookup cells, and looping over all of it would never end.
    fn occupied_part(&self, a: IVec3, b: IVec3) -> (IVec3, IVec3) {
        (a.max(self.origin), b.min(self.last))
    }

    /// The positions and channels of the particles `handlers`, in that order (a block's own
    /// copy, in the engines that work block by block).
    pub fn gather(&self, handlers: &[u32]) -> (Vec<Vec3>, Vec<Vec<f32>>) {
        let positions = handlers
            .iter()
            .map(|&h| self.positions[h as usize])
            .collect();
        let channels = self
            .channels
            .iter()
            .map(|c| handlers.iter().map(|&h| c[h as usize]).collect())
            .collect();
        (positions, channels)
    }

    pub fn heap_bytes(&self) -> usize {
        self.positions.capacity() * size_of::<Vec3>()
            + self
                .channels
                .iter()
                .map(|c| c.capacity() * size_of::<f32>())
                .sum::<usize>()
            + self.blocks.capacity() * (size_of::<(u64, CellBlock)>() + 1)
            + self.starts.capacity() * size_of::<u32>()
    }
}

/// The handlers of eq. 8, (cell id, particle index), sorted by cell id and then by index: the
/// order of a stable sort by cell id, so the same whichever sort made it.
enum Handlers {
    /// Each handler as `id << bits | index`, where ids and indices fit in 64 bits together (all
    /// but frames with particles far apart): sorted by a stable radix sort on the ids, in half
    /// the memory of pairs, so with its buffer in no more than the pairs sorted in place.
    Packed { handlers: Vec<u64>, bits: u32 },
    /// Pairs sorted in place, where the ids leave no room for the index.
    Pairs(Vec<(u64, u32)>),
}

/// Handlers are split into at most 2^PART_BITS parts by their ids' top bits, and the parts
/// sorted in parallel (cbd-large's whole handler-array stage, medians on 2 threads: 21 ms
/// with 4 096 parts, 24 with 256, 32 with one radix sort of the whole).
const PART_BITS: u32 = 12;

impl Handlers {
    /// The handlers of `particles`, whose cell ids `id` gives, none above `max_id`.
    fn sorted(particles: &[Vec3], id: impl Fn(Vec3) -> u64 + Sync, max_id: u64) -> Handlers {
        let indexed = particles.par_iter().enumerate();
        // Indices below the particle count fit in `bits`.
        let bits = u32::BITS - (particles.len() as u32).leading_zeros();
        if max_id.leading_zeros() >= bits {
            // Allocated before the keys, which then leave no hole below it when freed.
            let mut handlers = Vec::with_capacity(particles.len());
            let keys: Vec<u64> = indexed.map(|(i, &p)| id(p) << bits | i as u64).collect();
            // Split by the ids' top bits (a stable counting sort on all threads), then each
            // part radix-sorted by id (stable) on its own: one stable sort by id.
            let id_bits = u64::BITS - max_id.leading_zeros();
            let shift = bits + id_bits.saturating_sub(PART_BITS);
            let parts = (max_id << bits >> shift) as usize + 1;
            let part = |_, &h: &u64| Some(((h >> shift) as usize, h));
            // SAFETY: `part` is a function of its arguments.
            unsafe { sort_by_bucket_into(&keys, parts, part, &mut handlers) };
            drop(keys);
            handlers
                .par_chunk_by_mut(|a, b| a >> shift == b >> shift)
                .for_each(|part| radsort::sort_by_key(part, |&h| h >> bits));
            Handlers::Packed { handlers, bits }
        } else {
            let mut handlers: Vec<(u64, u32)> = indexed.map(|(i, &p)| (id(p), i as u32)).collect();
            handlers.par_sort_unstable();
            Handlers::Pairs(handlers)
        }
    }

    fn len(&self) -> usize {
        match self {
            Handlers::Packed { handlers, .. } => handlers.len(),
            Handlers::Pairs(handlers) => handlers.len(),
        }
    }

    /// Handler `k`: its cell id and particle index.
    #[inline]
    fn get(&self, k: usize) -> (u64, u32) {
        match self {
            Handlers::Packed { handlers, bits } => {
                let h = handlers[k];
                (h >> bits, (h & ((1 << bits) - 1)) as u32)
            }
            Handlers::Pairs(handlers) => handlers[k],
        }
    }
}

/// The cell of size `size` holding `p`, ⌊p / size⌋ on each axis saturated at i32's range, as
/// `(p / size).floor().as_ivec3()` gives it, but without a call to libm's `floorf` per
/// coordinate (x86-64 has no inline floor before SSE4.1).
#[inline]
pub(crate) fn cell_of(p: Vec3, size: f32) -> IVec3 {
    let q = p / size;
    IVec3::new(floor_i32(q.x), floor_i32(q.y), floor_i32(q.z))
}

/// `v.floor() as i32` without libm: truncated, then one less where that rounded up (a
/// negative fraction).
#[inline]
pub(crate) fn floor_i32(v: f32) -> i32 {
    let t = v as i32;
    t.saturating_sub(i32::from(t as f32 > v))
}

/// `v.ceil() as i32` without libm, as [`floor_i32`] floors: one more where truncating rounded
/// down (a positive fraction).
#[inline]
pub(crate) fn ceil_i32(v: f32) -> i32 {
    let t = v as i32;
    t.saturating_add(i32::from((t as f32) < v))
}

/// Z-order id of a non-negative cell coordinate (eq. 8), by bit spreading instead of the
/// paper's lookup table.
fn morton(c: IVec3) -> u64 {
    spread(c.x as u32) | (spread(c.y as u32) << 1) | (spread(c.z as u32) << 2)
}

fn spread(v: u32) -> u64 {
    let mut x = u64::from(v) & 0x1f_ffff;
    x = (x | (x << 32)) & 0x001f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x001f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn morton_interleaves_bits() {
        assert_eq!(morton(IVec3::new(1, 0, 0)), 1);
        assert_eq!(morton(IVec3::new(0, 1, 0)), 2);
        assert_eq!(morton(IVec3::new(0, 0, 1)), 4);
        assert_eq!(morton(IVec3::new(3, 3, 3)), 63);
        let m = (1 << AXIS_BITS) - 1;
        assert_eq!(morton(IVec3::new(m, m, m)), u64::MAX >> 1);
    }

    #[test]
    fn packed_and_paired_handlers_are_in_one_order() {
        let mut next = crate::tests::common::uniform(0x1405_7b7e_f767_814f);
        // Many particles per cell, duplicates among them, so that ties are broken by index.
        let mut ps: Vec<Vec3> = (0..30000)
            .map(|_| crate::tests::common::uniform_point(&mut next) * 3.0 - 1.0)
            .collect();
        ps.extend_from_within(100..2000);
        let (origin, size) = (IVec3::splat(-9), 0.125);
        let id = |p: Vec3| morton(cell_of(p, size) - origin);
        let mut expected: Vec<(u64, u32)> = (0..ps.len()).map(|i| (id(ps[i]), i as u32)).collect();
        expected.sort();
        let max_id = expected.last().unwrap().0;
        let packed = Handlers::sorted(&ps, id, max_id);
        assert!(matches!(packed, Handlers::Packed { .. }));
        // An id bound too large to pack leaves the pairs.
        let pairs = Handlers::sorted(&ps, id, u64::MAX);
        assert!(matches!(pairs, Handlers::Pairs(_)));
        for handlers in [packed, pairs] {
            let order: Vec<(u64, u32)> = (0..handlers.len()).map(|k| handlers.get(k)).collect();
            assert_eq!(order, expected);
        }
    }

    #[test]
    fn cells_are_the_floor_of_the_scaled_coordinates() {
        let mut next = crate::tests::common::uniform(0x5851_f42d_4c95_7f2d);
        let edges = [
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            -1.0e-30,
            8_388_607.5,
            -8_388_607.5,
            8_388_608.0,
            -8_388_609.0,
            2_147_483_520.0,
            -2_147_483_520.0,
            2_147_483_648.0,
            -2_147_483_648.0,
            -2_147_483_904.0,
            1.0e30,
            -1.0e30,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        let random = (0..20000).map(|i| (next() - 0.5) * 10f32.powi(i % 12));
        let values: Vec<f32> = edges.into_iter().chain(random).collect();
        for (i, &v) in values.iter().enumerate() {
            let p = Vec3::new(v, values[(i + 7) % values.len()], -v);
            for size in [1.0, 0.25, 0.013] {
                assert_eq!(
                    cell_of(p, size),
                    (p / size).floor().as_ivec3(),
                    "{p} / {size}"
                );
            }
        }
    }

    #[test]
    fn every_particle_is_found_in_its_cell() {
        let ps: Vec<Vec3> = (0..500)
            .map(|i| {
                Vec3::new(
                    (i % 7) as f32 * 0.3,
                    (i % 11) as f32 * -0.2,
                    (i % 13) as f32 * 0.1,
                )
            })
            .collect();
        let h = HandlerArray::new(&ps, 0.25).unwrap();
        let mut total = 0;
        h.for_each_in_box(Vec3::splat(-10.0), Vec3::splat(10.0), |c| total += c.len());
        assert_eq!(total, ps.len());
        for &p in &ps {
            assert!(h.cell(h.cell_of(p)).contains(&p));
        }
    }

    #[test]
    fn cell_loops_stay_within_the_particles() {
        let ps = [Vec3::new(0.1, 0.1, 0.1), Vec3::new(0.6, -0.3, 0.35)];
        let h = HandlerArray::new(&ps, 0.25).unwrap();
        // A box of i32's whole range (a brick of a cell 1e30 in lookup cells of 0.25) visits
        // the 3×3×2 occupied cells, not 2⁹⁶.
        let (a, b) = h.occupied_part(IVec3::MIN, IVec3::MAX);
        assert_eq!((a, b), (IVec3::new(0, -2, 0), IVec3::new(2, 0, 1)));
        let mut total = 0;
        h.for_each_in_box(Vec3::splat(-1e30), Vec3::splat(1e30), |c| total += c.len());
        assert_eq!(total, ps.len());
        let (a, b) = h.occupied_part(IVec3::splat(5), IVec3::splat(9));
        assert!(a.cmpgt(b).any(), "a box beside the particles is empty");
        let empty = HandlerArray::new(&[], 0.25).unwrap();
        let (a, b) = empty.occupied_part(IVec3::MIN, IVec3::MAX);
        assert!(a.cmpgt(b).all());
    }
}
