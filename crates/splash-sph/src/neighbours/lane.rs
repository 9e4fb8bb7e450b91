//! One lane or eight: the arithmetic a kernel term is written in once, so that `lane_sums!`
//! runs it on single floats and, written out in AVX2, on eight at a time with the same IEEE
//! operations (the compiler's own vectorising of the cubic spline's square root and clamps
//! mixed scalar, 4- and 8-wide steps and cost the density field a third of its sampling).

use std::ops::{Add, Div, Mul, Sub};

/// `f32`, or eight of them in an AVX2 register ([`F8`]).
pub trait Lane:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
    /// Floats per value: 1 or 8.
    const WIDTH: usize;
    fn splat(v: f32) -> Self;
    /// The first `WIDTH` floats of `v`.
    fn load(v: &[f32]) -> Self;
    /// Into the first `WIDTH` floats of `out`.
    fn store(self, out: &mut [f32]);
    /// `f` on each lane, for kernels written in scalar code only (exp, powi).
    fn map(self, f: impl Fn(f32) -> f32) -> Self;
    fn sqrt(self) -> Self;
    /// `f32::max` where `other` is not NaN: `other` wherever `self` is NaN.
    fn max(self, other: Self) -> Self;
    /// 1 where `lo < self < hi`, else 0 (NaN: 0).
    fn between(self, lo: f32, hi: f32) -> Self;
}

impl Lane for f32 {
    const WIDTH: usize = 1;
    #[inline(always)]
    fn splat(v: f32) -> f32 {
        v
    }
    #[inline(always)]
    fn load(v: &[f32]) -> f32 {
        v[0]
    }
    #[inline(always)]
    fn store(self, out: &mut [f32]) {
        out[0] = self;
    }
    #[inline(always)]
    fn map(self, f: impl Fn(f32) -> f32) -> f32 {
        f(self)
    }
    #[inline(always)]
    fn sqrt(self) -> f32 {
        f32::sqrt(self)
    }
    #[inline(always)]
    fn max(self, other: f32) -> f32 {
        f32::max(self, other)
    }
    #[inline(always)]
    fn between(self, lo: f32, hi: f32) -> f32 {
        if lo < self && self < hi { 1.0 } else { 0.0 }
    }
}

#[cfg(target_arch = "x86_64")]
pub use avx2::F8;

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use std::arch::x86_64::*;
    use std::ops::{Add, Div, Mul, Sub};

    use super::Lane;

    /// Eight lanes in an AVX2 register. Only functions compiled for AVX2 that run where the
    /// CPU has it make and use them (the AVX2 and AVX-512 paths of `lane_sums!`, the attribute
    /// means): that is what makes the intrinsics below sound, and why the type is not part of
    /// the public API.
    #[derive(Clone, Copy)]
    pub struct F8(__m256);

    impl F8 {
        #[inline(always)]
        pub fn to_array(self) -> [f32; 8] {
            let mut out = [0.0f32; 8];
            self.store(&mut out);
            out
        }
    }

    macro_rules! binary {
        ($trait:ident, $method:ident, $intrinsic:ident) => {
            impl $trait for F8 {
                type Output = F8;
                #[inline(always)]
                fn $method(self, other: F8) -> F8 {
                    // SAFETY: AVX2 is there (see the type).
                    F8(unsafe { $intrinsic(self.0, other.0) })
                }
            }
        };
    }
    binary!(Add, add, _mm256_add_ps);
    binary!(Sub, sub, _mm256_sub_ps);
    binary!(Mul, mul, _mm256_mul_ps);
    binary!(Div, div, _mm256_div_ps);

    impl Lane for F8 {
        const WIDTH: usize = 8;
        #[inline(always)]
        fn splat(v: f32) -> F8 {
            // SAFETY: AVX2 is there (see the type).
            F8(unsafe { _mm256_set1_ps(v) })
        }
        #[inline(always)]
        fn load(v: &[f32]) -> F8 {
            let v = &v[..8];
            // SAFETY: `v` holds 8 floats; AVX2 is there (see the type).
            F8(unsafe { _mm256_loadu_ps(v.as_ptr()) })
        }
        #[inline(always)]
        fn store(self, out: &mut [f32]) {
            let out = &mut out[..8];
            // SAFETY: `out` holds 8 floats; AVX2 is there (see the type).
            unsafe { _mm256_storeu_ps(out.as_mut_ptr(), self.0) }
        }
        #[inline(always)]
        fn map(self, f: impl Fn(f32) -> f32) -> F8 {
            F8::load(&self.to_array().map(f))
        }
        #[inline(always)]
        fn sqrt(self) -> F8 {
            // SAFETY: AVX2 is there (see the type).
            F8(unsafe { _mm256_sqrt_ps(self.0) })
        }
        /// maxps gives its second operand where either is NaN, as `f32::max` gives the one
        /// that is not.
        #[inline(always)]
        fn max(self, other: F8) -> F8 {
            // SAFETY: AVX2 is there (see the type).
            F8(unsafe { _mm256_max_ps(self.0, other.0) })
        }
        #[inline(always)]
        fn between(self, lo: f32, hi: f32) -> F8 {
            // SAFETY: AVX2 is there (see the type).
            F8(unsafe {
                let above = _mm256_cmp_ps::<_CMP_GT_OQ>(self.0, _mm256_set1_ps(lo));
                let below = _mm256_cmp_ps::<_CMP_LT_OQ>(self.0, _mm256_set1_ps(hi));
                _mm256_and_ps(_mm256_and_ps(above, below), _mm256_set1_ps(1.0))
            })
        }
    }
}
