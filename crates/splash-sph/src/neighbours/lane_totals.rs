//! The last step of [`lane_sums!`](crate::lane_sums): each sum's `LANES` accumulators added in
//! lane order, `((a[0] + a[1]) + a[2]) + … + a[7]`, as `a.iter().sum()` does. The vector path
//! adds the same numbers in the same order, but across eight sums at once: the accumulators are
//! transposed so that one vector holds lane l of eight sums (added one sum after another, the
//! reduction was 3 % of an SSP07 frame at cell r/2). It runs where the lane sums run on
//! AVX-512, whose 32 registers hold the loop's accumulators and the transpose; inlined into the
//! AVX2 path, the loop before it spilled more than this saved.

use super::neighbourhood::LANES;

/// Each sum's lanes added in lane order.
#[inline(always)]
pub fn lane_totals<const N: usize>(acc: &[[f32; LANES]; N]) -> [f32; N] {
    acc.map(|a| a.iter().sum::<f32>())
}

#[cfg(target_arch = "x86_64")]
pub use avx2::lane_totals_avx2;

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use std::arch::x86_64::*;

    use super::LANES;

    /// As [`super::lane_totals`], bit for bit: the sequential sums start from −0.0, which
    /// adds nothing, so each total here starts from lane 0.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn lane_totals_avx2<const N: usize>(acc: &[[f32; LANES]; N]) -> [f32; N] {
        let mut totals = [0.0f32; N];
        for (sums, out) in acc.chunks(8).zip(totals.chunks_mut(8)) {
            // SAFETY: each row is LANES = 8 floats.
            let rows: [__m256; 8] = std::array::from_fn(|k| match sums.get(k) {
                Some(row) => unsafe { _mm256_loadu_ps(row.as_ptr()) },
                None => _mm256_setzero_ps(),
            });
            let lanes = transpose(rows);
            let mut total = lanes[0];
            for lane in &lanes[1..] {
                total = _mm256_add_ps(total, *lane);
            }
            let mut t = [0.0f32; 8];
            // SAFETY: `t` holds 8 floats.
            unsafe { _mm256_storeu_ps(t.as_mut_ptr(), total) };
            out.copy_from_slice(&t[..out.len()]);
        }
        totals
    }

    /// The 8×8 transpose: lane l of the result k is lane k of `r[l]`.
    #[inline]
    #[target_feature(enable = "avx2")]
    fn transpose(r: [__m256; 8]) -> [__m256; 8] {
        // Pairs of rows interleaved, then quadruples, within each 128-bit half…
        let t = [
            _mm256_unpacklo_ps(r[0], r[1]),
            _mm256_unpackhi_ps(r[0], r[1]),
            _mm256_unpacklo_ps(r[2], r[3]),
            _mm256_unpackhi_ps(r[2], r[3]),
            _mm256_unpacklo_ps(r[4], r[5]),
            _mm256_unpackhi_ps(r[4], r[5]),
            _mm256_unpacklo_ps(r[6], r[7]),
            _mm256_unpackhi_ps(r[6], r[7]),
        ];
        let u = [
            _mm256_shuffle_ps::<0x44>(t[0], t[2]),
            _mm256_shuffle_ps::<0xee>(t[0], t[2]),
            _mm256_shuffle_ps::<0x44>(t[1], t[3]),
            _mm256_shuffle_ps::<0xee>(t[1], t[3]),
            _mm256_shuffle_ps::<0x44>(t[4], t[6]),
            _mm256_shuffle_ps::<0xee>(t[4], t[6]),
            _mm256_shuffle_ps::<0x44>(t[5], t[7]),
            _mm256_shuffle_ps::<0xee>(t[5], t[7]),
        ];
        // …then the halves of rows 0–3 and 4–7 joined.
        [
            _mm256_permute2f128_ps::<0x20>(u[0], u[4]),
            _mm256_permute2f128_ps::<0x20>(u[1], u[5]),
            _mm256_permute2f128_ps::<0x20>(u[2], u[6]),
            _mm256_permute2f128_ps::<0x20>(u[3], u[7]),
            _mm256_permute2f128_ps::<0x31>(u[0], u[4]),
            _mm256_permute2f128_ps::<0x31>(u[1], u[5]),
            _mm256_permute2f128_ps::<0x31>(u[2], u[6]),
            _mm256_permute2f128_ps::<0x31>(u[3], u[7]),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Accumulators of every sign and scale, zeros of both signs, and exact cancellations.
    fn accumulators<const N: usize>(next: &mut impl FnMut() -> f32) -> [[f32; LANES]; N] {
        std::array::from_fn(|_| {
            std::array::from_fn(|_| match (next() * 8.0) as u32 {
                0 => 0.0,
                1 => -0.0,
                2 => 1.0e-30 * (next() - 0.5),
                3 => 3.0e7 * (next() - 0.5),
                _ => (next() - 0.5) * (next() * 10.0).exp(),
            })
        })
    }

    fn check<const N: usize>(next: &mut impl FnMut() -> f32) -> usize {
        let mut acc: [[f32; LANES]; N] = accumulators(next);
        if next() < 0.1 {
            acc[0] = [-0.0; LANES];
        }
        // What `lane_sums!` returned before it had `lane_totals`.
        let sequential = acc.map(|a| a.iter().sum::<f32>().to_bits());
        assert_eq!(lane_totals(&acc).map(f32::to_bits), sequential);
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2, checked just above.
            let simd = unsafe { lane_totals_avx2(&acc) };
            assert_eq!(simd.map(f32::to_bits), sequential, "{acc:?}");
            return 1;
        }
        0
    }

    #[test]
    fn totals_equal_the_sequential_sums_bit_for_bit() {
        let mut next = crate::tests::common::uniform(0x2545_f491_4f6c_dd1d);
        let mut simd = 0;
        for _ in 0..500 {
            simd += check::<1>(&mut next);
            simd += check::<3>(&mut next);
            simd += check::<8>(&mut next);
            simd += check::<13>(&mut next);
            simd += check::<30>(&mut next);
        }
        if simd == 0 {
            eprintln!("no AVX2 on this CPU: only the scalar totals were checked");
        }
    }
}
