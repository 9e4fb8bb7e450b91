//! The particles within reach of a box, kept eight at a time with AVX2: eight particles tested
//! at once and the kept ones moved to the front of their lanes by one permutation from a table,
//! then stored in place. The gather per brick and the narrowing per block and per 2³ vertices
//! ran scalar and cost more than the kernel sums they serve (30 % of a frame at cell r/2).
//!
//! Every lane does the scalar path's IEEE operations in its order, so the same particles are
//! kept in the same order with the same coordinates, on every CPU.

use glam::Vec3;

/// Which particles a gather or a narrowing keeps: those within `radius` of `[lo, hi]`, or with
/// `own`, within the smaller of `radius` and the particle's value in channel `own`.
#[derive(Clone, Copy)]
pub struct Reach {
    pub lo: Vec3,
    pub hi: Vec3,
    pub radius: f32,
    pub own: Option<usize>,
}

#[cfg(target_arch = "x86_64")]
pub use avx2::{FRONT, Out, filter, gather};

/// The AVX2 paths, on x86-64 only (elsewhere the scalar paths run alone).
#[cfg(target_arch = "x86_64")]
mod avx2 {
    use std::arch::x86_64::*;
    use std::ops::Range;

    use glam::Vec3;

    use super::Reach;

    /// Lane permutations: entry `m` moves the lanes set in the 8-bit mask `m` to the front, in
    /// order.
    pub static FRONT: [[i32; 8]; 256] = {
        let mut table = [[0; 8]; 256];
        let mut m = 0;
        while m < 256 {
            let (mut lane, mut n) = (0, 0);
            while lane < 8 {
                if m >> lane & 1 == 1 {
                    table[m][n] = lane;
                    n += 1;
                }
                lane += 1;
            }
            m += 1;
        }
        table
    };

    /// Where kept particles go: three coordinate arrays and the channels, all of one length, each
    /// appended to.
    pub struct Out<'a> {
        pub xyz: [&'a mut Vec<f32>; 3],
        pub channels: &'a mut [Vec<f32>],
    }

    impl Out<'_> {
        /// Whether every array has room for `more` values beyond its length (the last stores
        /// spill up to 8 lanes past the kept particles).
        fn has_room(&self, more: usize) -> bool {
            let len = self.xyz[0].len();
            self.xyz
                .iter()
                .map(|v| &**v)
                .chain(self.channels.iter())
                .all(|v| v.len() == len && v.capacity() >= len + more)
        }
    }

    /// Appends the particles of `from` (padded to whole lanes) within reach, each shifted by
    /// `shift` first (the box is in shifted coordinates). `None` where the CPU lacks AVX2 (the
    /// caller then takes its scalar path).
    pub fn filter(
        from: [&[f32]; 3],
        from_channels: &[Vec<f32>],
        shift: Vec3,
        reach: Reach,
        out: Out,
    ) -> Option<()> {
        if !std::arch::is_x86_feature_detected!("avx2") {
            return None;
        }
        let len = from[0].len();
        assert!(len.is_multiple_of(8), "padded to whole lanes");
        assert!(from.iter().all(|v| v.len() == len));
        assert!(from_channels.iter().all(|v| v.len() == len));
        check(from_channels, &reach, &out, len + 8);
        // SAFETY: the CPU has AVX2 (checked above); reads stay within `len` of arrays that long,
        // writes within the room asserted.
        unsafe { filter_avx2(from, from_channels, shift, reach, out) };
        Some(())
    }

    /// Appends the particles of the `ranges` of `positions` (with `channels`) within reach,
    /// relative to `reach.lo`, in order, up to the first range that reaches into the arrays' last
    /// 8 particles, which it leaves; returns how many ranges it did. `None` where the CPU lacks
    /// AVX2.
    pub fn gather(
        positions: &[Vec3],
        channels: &[Vec<f32>],
        ranges: &[Range<usize>],
        reach: Reach,
        out: Out,
    ) -> Option<usize> {
        if !std::arch::is_x86_feature_detected!("avx2") {
            return None;
        }
        let total = positions.len();
        let done = ranges
            .iter()
            .position(|r| r.start + r.len().saturating_sub(1) / 8 * 8 + 8 > total)
            .unwrap_or(ranges.len());
        let ranges = &ranges[..done];
        assert!(ranges.iter().all(|r| r.end <= total));
        assert!(channels.iter().all(|v| v.len() == total));
        let room = ranges.iter().map(|r| r.len()).sum::<usize>() + 8;
        check(channels, &reach, &out, room);
        // SAFETY: as in `filter`; every chunk read lies within the arrays (the ranges left out
        // are those it would not).
        unsafe {
            gather_avx2(
                bytemuck::cast_slice(positions),
                channels,
                ranges,
                reach,
                out,
            )
        };
        Some(done)
    }

    fn check(channels: &[Vec<f32>], reach: &Reach, out: &Out, room: usize) {
        assert_eq!(out.channels.len(), channels.len());
        assert!(reach.own.is_none_or(|c| c < channels.len()));
        assert!(out.has_room(room));
    }

    /// Per-call constants of the lane test.
    struct Lanes {
        lo: [__m256; 3],
        hi: [__m256; 3],
        radius: __m256,
        r2: __m256,
    }

    impl Lanes {
        #[target_feature(enable = "avx2")]
        fn new(reach: &Reach) -> Lanes {
            let radius = _mm256_set1_ps(reach.radius);
            Lanes {
                lo: reach.lo.to_array().map(|v| _mm256_set1_ps(v)),
                hi: reach.hi.to_array().map(|v| _mm256_set1_ps(v)),
                radius,
                r2: _mm256_mul_ps(radius, radius),
            }
        }

        /// The lanes of `p` within reach, as a bit mask: |p − clamp(p, lo, hi)|² (summed as glam's
        /// length_squared, (x² + y²) + z²) against the reach squared.
        #[target_feature(enable = "avx2")]
        fn kept(&self, p: &[__m256; 3], own: Option<__m256>) -> usize {
            let d: [__m256; 3] = std::array::from_fn(|k| {
                let c = _mm256_min_ps(_mm256_max_ps(p[k], self.lo[k]), self.hi[k]);
                let d = _mm256_sub_ps(p[k], c);
                _mm256_mul_ps(d, d)
            });
            let d2 = _mm256_add_ps(_mm256_add_ps(d[0], d[1]), d[2]);
            let limit = own.map_or(self.r2, |own| {
                let r = _mm256_min_ps(own, self.radius);
                _mm256_mul_ps(r, r)
            });
            _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(d2, limit)) as usize
        }
    }

    /// The ends of the coordinate arrays of an [`Out`], written through pointers held in
    /// registers for a whole call: storing each array's length back every step made the next
    /// step wait for it (a third of the narrowing's time).
    struct Tail {
        xyz: [*mut f32; 3],
        kept: usize,
    }

    impl Tail {
        fn new(out: &mut Out) -> Tail {
            Tail {
                xyz: [0, 1, 2].map(|k| {
                    let v = &mut *out.xyz[k];
                    // SAFETY: `len` is within the allocation.
                    unsafe { v.as_mut_ptr().add(v.len()) }
                }),
                kept: 0,
            }
        }

        /// Sets the arrays' lengths to take the particles kept.
        fn finish(self, out: &mut Out) {
            for v in out.xyz.iter_mut() {
                // SAFETY: the `kept` values past the length were written (`store`).
                unsafe { v.set_len(v.len() + self.kept) };
            }
        }
    }

    /// Stores the lanes of `mask` of `p` at the tail, and of the channels at `i` (from
    /// `channels`) at the end of `out`'s.
    ///
    /// # Safety
    /// AVX2; `channels` readable at `i..i + 8`; `out` with room for 8 more beyond the tail.
    #[target_feature(enable = "avx2")]
    unsafe fn store(
        p: &[__m256; 3],
        channels: &[Vec<f32>],
        i: usize,
        mask: usize,
        tail: &mut Tail,
        out: &mut Out,
    ) {
        let front = unsafe { _mm256_loadu_si256(FRONT[mask].as_ptr().cast()) };
        for (&v, &p) in tail.xyz.iter().zip(p) {
            unsafe { _mm256_storeu_ps(v.add(tail.kept), _mm256_permutevar8x32_ps(p, front)) };
        }
        let kept = mask.count_ones() as usize;
        tail.kept += kept;
        for (v, from) in out.channels.iter_mut().zip(channels) {
            let n = v.len();
            unsafe {
                let c = _mm256_loadu_ps(from.as_ptr().add(i));
                _mm256_storeu_ps(v.as_mut_ptr().add(n), _mm256_permutevar8x32_ps(c, front));
                // SAFETY: the first `kept` lanes past the length were just written.
                v.set_len(n + kept);
            }
        }
    }

    #[target_feature(enable = "avx2")]
    unsafe fn filter_avx2(
        from: [&[f32]; 3],
        from_channels: &[Vec<f32>],
        shift: Vec3,
        reach: Reach,
        mut out: Out,
    ) {
        let lanes = Lanes::new(&reach);
        let s = shift.to_array().map(|v| _mm256_set1_ps(v));
        let mut tail = Tail::new(&mut out);
        for i in (0..from[0].len()).step_by(8) {
            // SAFETY (loads here and in `store`): i + 8 ≤ the arrays' padded length.
            let p: [__m256; 3] = std::array::from_fn(|k| unsafe {
                _mm256_add_ps(_mm256_loadu_ps(from[k].as_ptr().add(i)), s[k])
            });
            let own = reach
                .own
                .map(|c| unsafe { _mm256_loadu_ps(from_channels[c].as_ptr().add(i)) });
            let mask = lanes.kept(&p, own);
            unsafe { store(&p, from_channels, i, mask, &mut tail, &mut out) };
        }
        tail.finish(&mut out);
    }

    /// Splits 8 interleaved points (24 floats from three loads) into x, y and z lanes.
    #[target_feature(enable = "avx2")]
    fn deinterleave(a: __m256, b: __m256, c: __m256) -> [__m256; 3] {
        let order = |i: [i32; 8]| unsafe { _mm256_loadu_si256(i.as_ptr().cast()) };
        // x sits in lanes 0 3 6 of a, 1 4 7 of b, 2 5 of c; y and z one and two lanes on.
        let x = _mm256_blend_ps::<0b0010_0100>(_mm256_blend_ps::<0b1001_0010>(a, b), c);
        let y = _mm256_blend_ps::<0b0100_1001>(_mm256_blend_ps::<0b0010_0100>(a, b), c);
        let z = _mm256_blend_ps::<0b1001_0010>(_mm256_blend_ps::<0b0100_1001>(a, b), c);
        [
            _mm256_permutevar8x32_ps(x, order([0, 3, 6, 1, 4, 7, 2, 5])),
            _mm256_permutevar8x32_ps(y, order([1, 4, 7, 2, 5, 0, 3, 6])),
            _mm256_permutevar8x32_ps(z, order([2, 5, 0, 3, 6, 1, 4, 7])),
        ]
    }

    #[target_feature(enable = "avx2")]
    unsafe fn gather_avx2(
        xyz: &[f32],
        channels: &[Vec<f32>],
        ranges: &[Range<usize>],
        reach: Reach,
        mut out: Out,
    ) {
        let lanes = Lanes::new(&reach);
        let mut tail = Tail::new(&mut out);
        for range in ranges {
            // Lanes past the range are loaded but never kept.
            for i in range.clone().step_by(8) {
                // SAFETY (loads here and in `store`): i + 8 ≤ the arrays' length (see `gather`).
                let at = |k: usize| unsafe { _mm256_loadu_ps(xyz.as_ptr().add(3 * i + 8 * k)) };
                let p = deinterleave(at(0), at(1), at(2));
                let own = reach
                    .own
                    .map(|c| unsafe { _mm256_loadu_ps(channels[c].as_ptr().add(i)) });
                let valid = (1usize << (range.end - i).min(8)) - 1;
                let mask = lanes.kept(&p, own) & valid;
                let shifted: [__m256; 3] =
                    std::array::from_fn(|k| _mm256_sub_ps(p[k], lanes.lo[k]));
                unsafe { store(&shifted, channels, i, mask, &mut tail, &mut out) };
            }
        }
        tail.finish(&mut out);
    }
}
