//! Particles gathered once around a small region and reused by every query point in it: the
//! "neighbour lists reused across nearby vertices" that keep the hot loops branch-free.

use std::ops::Range;

use glam::{IVec3, Vec3};
use rayon::prelude::*;

#[cfg(target_arch = "x86_64")]
use super::box_filter;
use super::box_filter::Reach;
use super::handler_array::HandlerArray;

/// Width of the lane-parallel accumulators; the gathered arrays are padded to a multiple of it.
pub const LANES: usize = 8;

/// Padding coordinate: far outside every kernel, yet its square stays finite in f32, so that
/// `0 * d²` of a padded lane is 0 rather than NaN.
const FAR: f32 = 1.0e15;

/// Particle positions relative to an anchor point, as three coordinate arrays, with the
/// particles' attribute channels where the handler array has them (else `channels` stays
/// empty, and gathering costs nothing more than the positions).
#[derive(Default)]
pub struct Neighbourhood {
    pub anchor: Vec3,
    pub x: Vec<f32>,
    pub y: Vec<f32>,
    pub z: Vec<f32>,
    /// As `HandlerArray::channels`, for the gathered particles; padding holds 0.
    pub channels: Vec<Vec<f32>>,
    /// Scratch of [`Neighbourhood::filter_box`]: indices of the particles it keeps.
    kept: Vec<u32>,
    /// Scratch of the gathers: the handler-order ranges of the cells they visit.
    ranges: Vec<Range<usize>>,
}

impl Neighbourhood {
    /// Gathers every particle within `radius` of the box `[lo, hi]`, relative to `lo`; with
    /// `own_reach`, within the smaller of `radius` and each particle's value in that channel.
    pub fn gather_box(
        &mut self,
        handlers: &HandlerArray,
        lo: Vec3,
        hi: Vec3,
        radius: f32,
        own_reach: Option<usize>,
    ) {
        let (a, b) = (handlers.cell_of(lo - radius), handlers.cell_of(hi + radius));
        self.gather(handlers, (a, b), lo, hi, radius, own_reach);
    }

    /// Gathers every particle within `radius` of the handler array's lookup cell `cell`,
    /// relative to its lowest corner.
    pub fn gather_cell(&mut self, handlers: &HandlerArray, cell: IVec3, radius: f32) {
        let size = handlers.cell_size();
        let lo = cell.as_vec3() * size;
        // The cells within reach; the box's own edges need not round up a cell further.
        let k = IVec3::splat((radius / size).ceil() as i32);
        self.gather(handlers, (cell - k, cell + k), lo, lo + size, radius, None);
    }

    fn gather(
        &mut self,
        handlers: &HandlerArray,
        cells: (IVec3, IVec3),
        lo: Vec3,
        hi: Vec3,
        radius: f32,
        own_reach: Option<usize>,
    ) {
        self.clear(lo);
        self.channels.resize_with(handlers.channels.len(), Vec::new);
        let mut ranges = std::mem::take(&mut self.ranges);
        ranges.clear();
        handlers.for_each_in_cells(cells.0, cells.1, |range| ranges.push(range));
        let within = Reach {
            lo,
            hi,
            radius,
            own: own_reach,
        };
        let mut rest = &ranges[..];
        while !rest.is_empty() {
            #[cfg(target_arch = "x86_64")]
            if simd() {
                self.reserve(rest.iter().map(|r| r.len()).sum::<usize>() + LANES);
                let out = box_filter::Out {
                    xyz: [&mut self.x, &mut self.y, &mut self.z],
                    channels: &mut self.channels,
                };
                let positions = &handlers.positions;
                if let Some(done) =
                    box_filter::gather(positions, &handlers.channels, rest, within, out)
                {
                    rest = &rest[done..];
                    if rest.is_empty() {
                        break;
                    }
                }
            }
            // A cell among the arrays' last particles, which the SIMD path leaves (without it,
            // every cell).
            self.gather_range(handlers, rest[0].clone(), within);
            rest = &rest[1..];
        }
        self.ranges = ranges;
        self.pad();
    }

    /// Appends the particles `range` of `handlers` within reach, relative to `within.lo`.
    fn gather_range(&mut self, handlers: &HandlerArray, range: Range<usize>, within: Reach) {
        let (lo, hi) = (within.lo, within.hi);
        let reach = reach(&handlers.channels, within.radius, within.own);
        let start = self.x.len();
        self.grow(start + range.len());
        let mut n = start;
        for i in range {
            let p = handlers.positions[i];
            let r = reach(i);
            let kept = (p - p.clamp(lo, hi)).length_squared() <= r * r;
            n = self.put(n, p - lo, kept, |c| handlers.channels[c][i]);
        }
        self.truncate(n);
    }

    /// Keeps from `from` the particles within `radius` of the box `[lo, hi]`, relative to `lo`;
    /// with `own_reach`, within the smaller of `radius` and each particle's value in that
    /// channel.
    pub fn filter_box(
        &mut self,
        from: &Neighbourhood,
        lo: Vec3,
        hi: Vec3,
        radius: f32,
        own_reach: Option<usize>,
    ) {
        self.clear(lo);
        let shift = from.anchor - lo;
        let (blo, bhi) = (Vec3::ZERO, hi - lo);
        self.channels.resize_with(from.channels.len(), Vec::new);
        #[cfg(target_arch = "x86_64")]
        if simd() {
            self.reserve(from.len() + LANES);
            let within = Reach {
                lo: blo,
                hi: bhi,
                radius,
                own: own_reach,
            };
            let out = box_filter::Out {
                xyz: [&mut self.x, &mut self.y, &mut self.z],
                channels: &mut self.channels,
            };
            let xyz = [&from.x[..], &from.y, &from.z];
            if box_filter::filter(xyz, &from.channels, shift, within, out).is_some() {
                self.pad();
                return;
            }
        }
        let at = |i: usize| Vec3::new(from.x[i], from.y[i], from.z[i]) + shift;
        let outside = |p: Vec3| (p - p.clamp(blo, bhi)).length_squared();
        // The indices kept, compacted branch-free, then each array gathered once.
        let kept = &mut self.kept;
        kept.clear();
        kept.resize(from.len(), 0);
        let mut n = 0;
        match own_reach {
            None => {
                let r2 = radius * radius;
                for i in 0..from.len() {
                    kept[n] = i as u32;
                    n += usize::from(outside(at(i)) <= r2);
                }
            }
            Some(c) => {
                for (i, own) in from.channels[c].iter().enumerate() {
                    let r = own.min(radius);
                    kept[n] = i as u32;
                    n += usize::from(outside(at(i)) <= r * r);
                }
            }
        }
        kept.truncate(n);
        let shifted = |v: &[f32], s: f32, out: &mut Vec<f32>| {
            out.extend(kept.iter().map(|&i| v[i as usize] + s));
        };
        shifted(&from.x, shift.x, &mut self.x);
        shifted(&from.y, shift.y, &mut self.y);
        shifted(&from.z, shift.z, &mut self.z);
        for (out, v) in self.channels.iter_mut().zip(&from.channels) {
            out.extend(kept.iter().map(|&i| v[i as usize]));
        }
        self.pad();
    }

    /// Branch-free compaction: writes a particle (position `q`, channel values `channel(c)`)
    /// into slot `n` and returns the next free slot, which stays `n` unless it is `kept`, so
    /// that the next particle overwrites a rejected one.
    #[inline(always)]
    fn put(&mut self, n: usize, q: Vec3, kept: bool, channel: impl Fn(usize) -> f32) -> usize {
        (self.x[n], self.y[n], self.z[n]) = (q.x, q.y, q.z);
        for (c, values) in self.channels.iter_mut().enumerate() {
            values[n] = channel(c);
        }
        n + usize::from(kept)
    }

    /// Room for `more` values past the end of every array.
    #[cfg(target_arch = "x86_64")]
    fn reserve(&mut self, more: usize) {
        for v in [&mut self.x, &mut self.y, &mut self.z]
            .into_iter()
            .chain(&mut self.channels)
        {
            v.reserve(more);
        }
    }

    fn grow(&mut self, len: usize) {
        self.x.resize(len, 0.0);
        self.y.resize(len, 0.0);
        self.z.resize(len, 0.0);
        for c in &mut self.channels {
            c.resize(len, 0.0);
        }
    }

    /// Holds the `candidates` (index into `positions` and `channels`, and whether to keep it)
    /// that are kept, relative to `anchor`.
    pub fn pick(
        &mut self,
        anchor: Vec3,
        candidates: impl ExactSizeIterator<Item = (usize, bool)>,
        positions: &[Vec3],
        channels: &[Vec<f32>],
    ) {
        self.channels.resize_with(channels.len(), Vec::new);
        self.clear(anchor);
        self.grow(candidates.len());
        let mut n = 0;
        for (i, kept) in candidates {
            n = self.put(n, positions[i] - anchor, kept, |c| channels[c][i]);
        }
        self.truncate(n);
        self.pad();
    }

    /// Holds exactly `points`, relative to `anchor`, without channels (the tests' brute force).
    #[cfg(test)]
    pub fn set(&mut self, anchor: Vec3, points: &[Vec3]) {
        self.clear(anchor);
        self.channels.clear();
        for &p in points {
            self.push(p - anchor);
        }
        self.pad();
    }

    fn clear(&mut self, anchor: Vec3) {
        self.anchor = anchor;
        self.x.clear();
        self.y.clear();
        self.z.clear();
        for c in &mut self.channels {
            c.clear();
        }
    }

    fn truncate(&mut self, n: usize) {
        self.x.truncate(n);
        self.y.truncate(n);
        self.z.truncate(n);
        for c in &mut self.channels {
            c.truncate(n);
        }
    }

    fn push(&mut self, p: Vec3) {
        self.x.push(p.x);
        self.y.push(p.y);
        self.z.push(p.z);
    }

    fn pad(&mut self) {
        while !self.x.len().is_multiple_of(LANES) {
            self.push(Vec3::splat(FAR));
            for c in &mut self.channels {
                c.push(0.0);
            }
        }
    }

    pub fn len(&self) -> usize {
        self.x.len()
    }
}

/// Whether the AVX2 paths may run (where the CPU has AVX2); tests turn them off to compare the
/// scalar paths with them.
#[cfg(target_arch = "x86_64")]
fn simd() -> bool {
    #[cfg(test)]
    return !tests::SCALAR.get();
    #[cfg(not(test))]
    true
}

/// Particle i's reach: `radius`, or with `own_reach` the smaller of it and the particle's
/// value in that channel.
pub fn reach(
    channels: &[Vec<f32>],
    radius: f32,
    own_reach: Option<usize>,
) -> impl Fn(usize) -> f32 + '_ {
    move |i| own_reach.map_or(radius, |c| channels[c][i].min(radius))
}

/// Maps every particle, in handler order, to `f(near, x)`: `near` holds the particles within
/// `radius` of the particle's lookup cell, gathered once per cell and reused by all its
/// particles, and `x` is the particle's position relative to `near.anchor`.
pub fn map_particles<T: Send>(
    handlers: &HandlerArray,
    radius: f32,
    f: impl Fn(&Neighbourhood, Vec3) -> T + Sync,
) -> Vec<T> {
    handlers
        .positions
        .par_iter()
        .map_init(
            || (Neighbourhood::default(), None),
            |(near, cached), &p| {
                let cell = handlers.cell_of(p);
                if *cached != Some(cell) {
                    near.gather_cell(handlers, cell, radius);
                    *cached = Some(cell);
                }
                f(near, p - near.anchor)
            },
        )
        .collect()
}

#[cfg(test)]
pub(crate) mod tests {
    use std::cell::Cell;

    use super::*;

    thread_local!(pub static SCALAR: Cell<bool> = const { Cell::new(false) });

    /// Runs `f` on the scalar paths, then on the AVX2 ones where the CPU has them.
    fn both<T>(mut f: impl FnMut() -> T) -> (T, T) {
        SCALAR.set(true);
        let scalar = f();
        SCALAR.set(false);
        (scalar, f())
    }

    fn arrays(n: &Neighbourhood) -> Vec<Vec<u32>> {
        let bits = |v: &Vec<f32>| v.iter().map(|x| x.to_bits()).collect();
        [&n.x, &n.y, &n.z]
            .into_iter()
            .chain(&n.channels)
            .map(bits)
            .collect()
    }

    /// A cloud with a per-particle reach channel and a second channel, some particles exactly
    /// on box faces, and cells of all sizes (the last cell of the array included).
    fn cloud() -> HandlerArray {
        let mut next = crate::tests::common::uniform(0x9e37_79b9_7f4a_7c15u64);
        let mut points: Vec<Vec3> = (0..20000)
            .map(|_| crate::tests::common::uniform_point(&mut next) * 2.0 - 0.5)
            .collect();
        points.extend((0..40).map(|i| Vec3::new(0.25, i as f32 / 40.0, 0.5)));
        let reach: Vec<f32> = points.iter().map(|_| 0.05 + 0.3 * next()).collect();
        let other: Vec<f32> = points.iter().map(|_| next()).collect();
        HandlerArray::with_channels(&points, 0.125, vec![reach, other]).unwrap()
    }

    #[test]
    fn simd_gathers_and_filters_equal_the_scalar_ones_bit_for_bit() {
        let h = cloud();
        let boxes = [
            (Vec3::splat(0.25), Vec3::new(0.5, 0.375, 0.75), 0.2),
            (Vec3::new(-0.3, 0.1, 0.2), Vec3::new(-0.25, 0.1, 0.2), 0.3),
            (Vec3::splat(1.4), Vec3::splat(1.6), 0.25),
        ];
        for (lo, hi, radius) in boxes {
            for own in [None, Some(0)] {
                let (a, b) = both(|| {
                    let mut near = Neighbourhood::default();
                    near.gather_box(&h, lo, hi, radius, own);
                    let mut narrow = Neighbourhood::default();
                    let mid = (lo + hi) / 2.0;
                    narrow.filter_box(&near, lo, mid, radius * 0.6, own);
                    (arrays(&near), arrays(&narrow))
                });
                assert_eq!(a, b, "box {lo}..{hi}, own reach {own:?}");
                assert!(
                    a.0[0].len() > 8 && a.1[0].len() > 8,
                    "the box keeps particles: {} {}",
                    a.0[0].len(),
                    a.1[0].len()
                );
                assert!(a.1[0].len() < a.0[0].len(), "the narrower box keeps fewer");
            }
        }
        let (a, b) = both(|| {
            let mut near = Neighbourhood::default();
            near.gather_cell(&h, IVec3::new(2, 2, 2), 0.2);
            arrays(&near)
        });
        assert_eq!(a, b);
    }
}
