//! Sums over a gathered neighbourhood in `LANES` independent lanes ([`lane_sums!`]), compiled
//! for scalar, AVX2 and AVX-512 code and chosen at run time, the same bits on every path.
//!
//! Their last step, [`lane_totals`]: each sum's `LANES` accumulators added in
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

/// The widest code [`lane_sums!`] is compiled for that the CPU runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Lanes {
    Scalar,
    #[cfg(target_arch = "x86_64")]
    Avx2,
    #[cfg(target_arch = "x86_64")]
    Avx512,
}

/// Which of the [`lane_sums!`] paths runs: the widest the CPU has, or the one a test chose.
#[inline]
pub fn lanes_path() -> Lanes {
    #[cfg(test)]
    if let Some(path) = tests::FORCED.get() {
        return path;
    }
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::is_x86_feature_detected as has;
        if has!("avx512f") && has!("avx512vl") {
            return Lanes::Avx512;
        }
        if has!("avx2") {
            return Lanes::Avx2;
        }
    }
    Lanes::Scalar
}

/// Defines `fn NAME(near: &Neighbourhood, x: Vec3, PARAM: TYPE) -> [f32; N]`, returning
/// Σ_j TERM over the particles of `near`, where TERM sees `dx, dy, dz` = x_j − x (and, when a
/// fourth name is given, the particle's channel 0, e.g. its volume) and gives N values. The
/// sums run in `LANES` independent lanes so that the loop vectorises, compiled once more for
/// AVX2 and AVX-512 and chosen at run time; every lane does the same IEEE operations in the
/// same order on every path, so results do not depend on the CPU or the thread count. TERM
/// must give 0 for the padding (beyond any kernel's support) and should not branch.
///
/// `vector fn` instead of `fn`: TERM is written over a [`Lane`](super::lane::Lane) type and
/// runs on eight lanes at once in AVX2 ([`F8`](super::lane::F8)) instead of being left to
/// the compiler's vectoriser, for terms it vectorises badly (square roots, clamps).
///
/// A macro rather than a function taking a closure: a closure is compiled without the AVX2
/// feature and would not be inlined into the AVX2 loop.
macro_rules! lane_sums {
    ($(#[$attr:meta])* $vis:vis fn $name:ident($p:ident: $ty:ty) -> [$n:expr] |$dx:ident, $dy:ident, $dz:ident $(, $v:ident)?| $term:block) => {
        $crate::neighbours::lane_sums::lane_sums!(@emit auto $(#[$attr])* $vis fn $name($p: $ty) -> [$n] |$dx, $dy, $dz $(, $v)?| $term);
    };
    ($(#[$attr:meta])* $vis:vis vector fn $name:ident($p:ident: $ty:ty) -> [$n:expr] |$dx:ident, $dy:ident, $dz:ident $(, $v:ident)?| $term:block) => {
        $crate::neighbours::lane_sums::lane_sums!(@emit vector $(#[$attr])* $vis fn $name($p: $ty) -> [$n] |$dx, $dy, $dz $(, $v)?| $term);
    };
    // The AVX2 and AVX-512 paths' sums: the scalar lanes, compiled for them.
    (@wide auto $near:ident, $x:ident, $p:ident, $n:expr, |$dx:ident, $dy:ident, $dz:ident $(, $v:ident)?| $term:block) => {
        lanes($near, $x, $p)
    };
    // …or eight lanes at a time in F8.
    (@wide vector $near:ident, $x:ident, $p:ident, $n:expr, |$dx:ident, $dy:ident, $dz:ident $(, $v:ident)?| $term:block) => {{
        use $crate::neighbours::lane::{F8, Lane};
        let at = [F8::splat($x.x), F8::splat($x.y), F8::splat($x.z)];
        let mut acc = [F8::splat(0.0); $n];
        // Channel 0 where the term takes it (else x again, unused).
        let _first: &[f32] = &$near.x;
        $( let _first: &[f32] = &$near.channels[0]; stringify!($v); )?
        // An index loop whose loads are F8::load inlined here, not zipped iterators: their
        // next() is generic code compiled without AVX, which LLVM may leave out of line
        // (it did once F8::chunks mapped through F8::load); then every step called it and
        // the load intrinsic, and the call spilled the accumulators, as the calling
        // convention keeps no vector register.
        let len = $near.x.len().min($near.y.len()).min($near.z.len()).min(_first.len());
        let (xs, ys, zs) = (&$near.x[..len], &$near.y[..len], &$near.z[..len]);
        let channel = &_first[..len];
        let mut i = 0;
        while i + 8 <= len {
            let (cx, cy, cz) = (F8::load(&xs[i..]), F8::load(&ys[i..]), F8::load(&zs[i..]));
            let _channel = F8::load(&channel[i..]);
            i += 8;
            let ($dx, $dy, $dz) = (cx - at[0], cy - at[1], cz - at[2]);
            $( let $v = _channel; )?
            let lane: [F8; $n] = $term;
            for (a, t) in acc.iter_mut().zip(lane) {
                *a = *a + t;
            }
        }
        acc.map(F8::to_array)
    }};
    (@emit $kind:ident $(#[$attr:meta])* $vis:vis fn $name:ident($p:ident: $ty:ty) -> [$n:expr] |$dx:ident, $dy:ident, $dz:ident $(, $v:ident)?| $term:block) => {
        $(#[$attr])*
        $vis fn $name(
            near: &$crate::neighbours::neighbourhood::Neighbourhood,
            x: glam::Vec3,
            $p: $ty,
        ) -> [f32; $n] {
            use $crate::neighbours::neighbourhood::LANES;
            #[inline(always)]
            fn lanes(
                near: &$crate::neighbours::neighbourhood::Neighbourhood,
                x: glam::Vec3,
                $p: $ty,
            ) -> [[f32; LANES]; $n] {
                let mut acc = [[0.0f32; LANES]; $n];
                let n = near.len() / LANES;
                for i in 0..n {
                    let r = i * LANES..(i + 1) * LANES;
                    $( let $v = &near.channels[0][r.clone()]; )?
                    let (cx, cy, cz) = (&near.x[r.clone()], &near.y[r.clone()], &near.z[r]);
                    let mut terms = [[0.0f32; LANES]; $n];
                    for l in 0..LANES {
                        let ($dx, $dy, $dz) = (cx[l] - x.x, cy[l] - x.y, cz[l] - x.z);
                        $( let $v = $v[l]; )?
                        let lane = $term;
                        for (term, v) in terms.iter_mut().zip(lane) {
                            term[l] = v;
                        }
                    }
                    for (a, t) in acc.iter_mut().zip(&terms) {
                        for l in 0..LANES {
                            a[l] += t[l];
                        }
                    }
                }
                acc
            }
            use $crate::neighbours::lane_sums::lane_totals;
            #[cfg(target_arch = "x86_64")]
            #[target_feature(enable = "avx2")]
            unsafe fn lanes_avx2(
                near: &$crate::neighbours::neighbourhood::Neighbourhood,
                x: glam::Vec3,
                $p: $ty,
            ) -> [f32; $n] {
                let acc = $crate::neighbours::lane_sums::lane_sums!(@wide $kind near, x, $p, $n, |$dx, $dy, $dz $(, $v)?| $term);
                lane_totals(&acc)
            }
            // With AVX-512's 32 vector registers the accumulators of many sums (SSP07's 13)
            // stay in registers instead of going through the stack every step.
            #[cfg(target_arch = "x86_64")]
            #[target_feature(enable = "avx512f,avx512vl")]
            unsafe fn lanes_avx512(
                near: &$crate::neighbours::neighbourhood::Neighbourhood,
                x: glam::Vec3,
                $p: $ty,
            ) -> [f32; $n] {
                let acc = $crate::neighbours::lane_sums::lane_sums!(@wide $kind near, x, $p, $n, |$dx, $dy, $dz $(, $v)?| $term);
                // The totals transposed: with 32 registers the lane loop keeps its own.
                $crate::neighbours::lane_sums::lane_totals_avx2(&acc)
            }
            use $crate::neighbours::lane_sums::{Lanes, lanes_path};
            match lanes_path() {
                // SAFETY: the CPU has AVX-512 F and VL, as `lanes_path` checked.
                #[cfg(target_arch = "x86_64")]
                Lanes::Avx512 => unsafe { lanes_avx512(near, x, $p) },
                // SAFETY: the CPU has AVX2, as `lanes_path` checked.
                #[cfg(target_arch = "x86_64")]
                Lanes::Avx2 => unsafe { lanes_avx2(near, x, $p) },
                Lanes::Scalar => lane_totals(&lanes(near, x, $p)),
            }
        }
    };
}
pub(crate) use lane_sums;

#[cfg(test)]
pub(crate) mod tests {
    use std::cell::Cell;

    use super::*;

    // The lane path a test forces `lanes_path` to choose, if any.
    thread_local!(pub static FORCED: Cell<Option<Lanes>> = const { Cell::new(None) });

    /// `f` run on every lane path this CPU has, scalar first, with `lanes_path` forced to it.
    pub fn on_every_path<T>(mut f: impl FnMut() -> T) -> Vec<(Lanes, T)> {
        let mut paths = vec![Lanes::Scalar];
        #[cfg(target_arch = "x86_64")]
        paths.extend(match lanes_path() {
            Lanes::Avx512 => vec![Lanes::Avx2, Lanes::Avx512],
            Lanes::Avx2 => vec![Lanes::Avx2],
            Lanes::Scalar => vec![],
        });
        paths
            .into_iter()
            .map(|path| {
                FORCED.set(Some(path));
                let out = f();
                FORCED.set(None);
                (path, out)
            })
            .collect()
    }

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
