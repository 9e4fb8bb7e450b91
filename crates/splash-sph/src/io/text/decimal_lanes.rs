//! Decimal text of eight numbers at once in AVX-512 lanes, the same as `float_text`'s scalar
//! path gives, which prints the numbers the lanes leave: Schubfach (Giulietti 2020, sections
//! 8–9) for `f32`s (each float's shortest decimal d·10^e with d's digits as text; left: outside
//! 2^-26 ≤ |x| < 2^24, powers of two, ties, zeros, infinities, NaN), and integers below 10^8.

/// Numbers per call: three vectors of eight lanes, whose independent dependency chains the
/// CPU runs side by side (one alone waits on its chain's latency).
pub(super) const BLOCK: usize = 24;

/// [`BLOCK`] floats' shortest decimals d·10^e, for `float_text` to place.
#[derive(Clone, Copy)]
pub(super) struct Decimals {
    /// d's digits in ASCII, the first in the lowest byte, then '0's: bytes 0–7 of the text.
    pub low: [u64; BLOCK],
    /// Bytes 8–15 of the text.
    pub high: [u64; BLOCK],
    /// d's digit count, trailing zeros dropped unless the float is whole.
    pub digits: [u64; BLOCK],
    /// e.
    pub exponent: [i64; BLOCK],
    /// Lane i's bit set: the lane is left to the scalar path.
    pub scalar: u32,
}

impl Decimals {
    /// No numbers yet.
    pub const EMPTY: Self = Self {
        low: [0; BLOCK],
        high: [0; BLOCK],
        digits: [0; BLOCK],
        exponent: [0; BLOCK],
        scalar: 0,
    };
}

/// [`BLOCK`] integers' decimal digits, for `float_text` to place.
#[derive(Clone, Copy)]
pub(super) struct Integers {
    /// The digits in ASCII, the first in the lowest byte, then '0's.
    pub text: [u64; BLOCK],
    /// Their count.
    pub digits: [u64; BLOCK],
    /// Lane i's bit set: the integer has 9 digits or more, left to the scalar path.
    pub scalar: u32,
}

impl Integers {
    /// No numbers yet.
    pub const EMPTY: Self = Self {
        text: [0; BLOCK],
        digits: [0; BLOCK],
        scalar: 0,
    };
}

/// Whether this CPU has the lanes.
pub(super) fn available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx512f")
            && std::arch::is_x86_feature_detected!("avx512dq")
            && std::arch::is_x86_feature_detected!("avx512cd")
            && std::arch::is_x86_feature_detected!("avx512bw")
    }
    #[cfg(not(target_arch = "x86_64"))]
    false
}

/// The decimals of `x` into `out`; only where [`available`] says so.
pub(super) fn decimals(x: &[f32; BLOCK], out: &mut Decimals) {
    #[cfg(target_arch = "x86_64")]
    {
        assert!(available(), "AVX-512 F, DQ, CD and BW");
        // SAFETY: the CPU has the features, checked just above.
        unsafe { avx512::decimals(x, out) }
    }
    #[cfg(not(target_arch = "x86_64"))]
    unreachable!("no lanes on this architecture ({x:?})")
}

/// The digits of `v + offset` for each `v` into `out`; only where [`available`] says so.
pub(super) fn integers(v: &[u32; BLOCK], offset: u32, out: &mut Integers) {
    #[cfg(target_arch = "x86_64")]
    {
        assert!(available(), "AVX-512 F, DQ, CD and BW");
        // SAFETY: the CPU has the features, checked just above.
        unsafe { avx512::integers(v, offset, out) }
    }
    #[cfg(not(target_arch = "x86_64"))]
    unreachable!("no lanes on this architecture ({v:?}, {offset})")
}

/// Powers of five up to 5^15.
pub(super) const POW5: [u64; 16] = {
    let mut p = [1u64; 16];
    let mut k = 1;
    while k < 16 {
        p[k] = p[k - 1] * 5;
        k += 1;
    }
    p
};

#[cfg(target_arch = "x86_64")]
mod avx512 {
    use std::arch::x86_64::*;

    use super::{BLOCK, Decimals, Integers, POW5};

    /// Eight `'0'`s, as the bytes of a little-endian `u64`.
    const ZEROS8: i64 = i64::from_le_bytes([b'0'; 8]);

    #[inline]
    #[target_feature(enable = "avx512f")]
    fn splat(v: i64) -> __m512i {
        _mm512_set1_epi64(v)
    }

    /// v / 2^sh rounded to odd (a sticky low bit for any fraction), sh < 64.
    #[inline]
    #[target_feature(enable = "avx512f")]
    fn round_to_odd(v: __m512i, sh: __m512i, below: __m512i) -> __m512i {
        let fraction = _mm512_test_epi64_mask(v, below);
        _mm512_mask_or_epi64(
            _mm512_srlv_epi64(v, sh),
            fraction,
            _mm512_srlv_epi64(v, sh),
            splat(1),
        )
    }

    /// The 8 decimal digits of each v < 10^8, leading zeros included, as byte values 0–9, the
    /// first digit in the lowest byte: the scalar `digits8`'s lane splitting, in lanes of 32
    /// and 16 bits (64-bit multiplies cost several times more).
    #[inline]
    #[target_feature(enable = "avx512f,avx512bw")]
    fn digits8(v: __m512i) -> __m512i {
        // v / 10^4 for v < 2^32.
        let quarter = _mm512_srli_epi64::<45>(_mm512_mul_epu32(v, splat(0xd1b7_1759)));
        let y = _mm512_or_si512(
            quarter,
            _mm512_slli_epi64::<32>(_mm512_sub_epi64(
                v,
                _mm512_mul_epu32(quarter, splat(10_000)),
            )),
        );
        // ⌊y/100⌋ as y·10486 >> 20, exact below 10^4.
        let high = _mm512_srli_epi32::<20>(_mm512_mullo_epi32(y, _mm512_set1_epi32(10_486)));
        let low = _mm512_sub_epi32(y, _mm512_mullo_epi32(high, _mm512_set1_epi32(100)));
        let y = _mm512_or_si512(high, _mm512_slli_epi32::<16>(low));
        // ⌊y/10⌋ as y·103 >> 10, exact below 100.
        let high = _mm512_srli_epi16::<10>(_mm512_mullo_epi16(y, _mm512_set1_epi16(103)));
        let low = _mm512_sub_epi16(y, _mm512_mullo_epi16(high, _mm512_set1_epi16(10)));
        _mm512_or_si512(high, _mm512_slli_epi16::<8>(low))
    }

    /// The scalar `digits8_text` lane by lane, for integers below 10^8.
    #[target_feature(enable = "avx512f,avx512dq,avx512cd,avx512bw")]
    pub(super) fn integers(v: &[u32; BLOCK], offset: u32, out: &mut Integers) {
        out.scalar = 0;
        for (group, v) in v.chunks_exact(8).enumerate() {
            integers8(v.try_into().expect("8 lanes"), offset, out, 8 * group);
        }
    }

    /// [`integers`] of 8 lanes into `out` from `at`.
    #[inline]
    #[target_feature(enable = "avx512f,avx512dq,avx512cd,avx512bw")]
    fn integers8(v: &[u32; 8], offset: u32, out: &mut Integers, at: usize) {
        // SAFETY: reads the 32 bytes of `v`.
        let v = _mm512_cvtepu32_epi64(unsafe { _mm256_loadu_si256(v.as_ptr().cast()) });
        let v = _mm512_add_epi64(v, splat(i64::from(offset)));
        let scalar = _mm512_cmpge_epu64_mask(v, splat(100_000_000));
        let raw = digits8(v);
        // Leading zero digits: the zero bytes at the low end, at most 7 (v = 0 is "0").
        let lowest = _mm512_and_si512(raw, _mm512_sub_epi64(_mm512_setzero_si512(), raw));
        let leading_bits = _mm512_min_epu64(
            _mm512_and_si512(
                _mm512_sub_epi64(splat(63), _mm512_lzcnt_epi64(lowest)),
                splat(!7),
            ),
            splat(56),
        );
        out.scalar |= u32::from(scalar) << at;
        let text = _mm512_or_si512(_mm512_srlv_epi64(raw, leading_bits), splat(ZEROS8));
        let digits = _mm512_sub_epi64(splat(8), _mm512_srli_epi64::<3>(leading_bits));
        // SAFETY: each store writes the 64 bytes of 8 lanes.
        unsafe {
            _mm512_storeu_si512(out.text[at..at + 8].as_mut_ptr().cast(), text);
            _mm512_storeu_si512(out.digits[at..at + 8].as_mut_ptr().cast(), digits);
        }
    }

    /// The scalar `schubfach` and `digits9_trailing`/`digits8_text` of `float_text`, lane by
    /// lane.
    #[target_feature(enable = "avx512f,avx512dq,avx512cd,avx512bw")]
    pub(super) fn decimals(x: &[f32; BLOCK], out: &mut Decimals) {
        out.scalar = 0;
        for (group, x) in x.chunks_exact(8).enumerate() {
            decimals8(x.try_into().expect("8 lanes"), out, 8 * group);
        }
    }

    /// [`decimals`] of 8 lanes into `out` from `at`, in 64 bits (the scalar path's `scaled`
    /// for k ≥ −15, that is shift ≤ 49).
    #[inline]
    #[target_feature(enable = "avx512f,avx512dq,avx512cd,avx512bw")]
    fn decimals8(x: &[f32; 8], out: &mut Decimals, at: usize) {
        let (zero, one) = (_mm512_setzero_si512(), splat(1));
        // SAFETY: reads the 32 bytes of `x`.
        let bits = _mm512_cvtepu32_epi64(unsafe { _mm256_loadu_si256(x.as_ptr().cast()) });
        let biased = _mm512_and_si512(_mm512_srli_epi64::<23>(bits), splat(0xff));
        let fraction = _mm512_and_si512(bits, splat(0x7f_ffff));
        // |x| = c·2^−shift.
        let shift = _mm512_sub_epi64(splat(150), biased);
        let outside = _mm512_cmpeq_epi64_mask(fraction, zero)
            | _mm512_cmplt_epi64_mask(shift, one)
            | _mm512_cmpgt_epi64_mask(shift, splat(49));
        let c = _mm512_or_si512(fraction, splat(1 << 23));
        let below_shift = _mm512_sub_epi64(_mm512_sllv_epi64(one, shift), one);
        let whole =
            _mm512_cmple_epi64_mask(shift, splat(23)) & _mm512_testn_epi64_mask(c, below_shift);
        // k = −⌈shift·log10 2⌉ = −(⌊shift·1233 / 2^12⌋ + 1) (never a whole number).
        let k = _mm512_sub_epi64(
            zero,
            _mm512_add_epi64(
                _mm512_srli_epi64::<12>(_mm512_mul_epu32(shift, splat(1233))),
                one,
            ),
        );
        let index = _mm512_and_si512(_mm512_sub_epi64(zero, k), splat(15));
        // SAFETY: reads the 128 bytes of POW5.
        let (pow_low, pow_high) = unsafe {
            (
                _mm512_loadu_si512(POW5.as_ptr().cast()),
                _mm512_loadu_si512(POW5.as_ptr().add(8).cast()),
            )
        };
        let scale = _mm512_permutex2var_epi64(pow_low, index, pow_high);
        // 4c·10^k·2^−shift = 4c·5^k·2^−(shift+k).
        let sh = _mm512_add_epi64(shift, k);
        let below = _mm512_sub_epi64(_mm512_sllv_epi64(one, sh), one);
        let v = _mm512_mullo_epi64(_mm512_slli_epi64::<2>(c), scale);
        let two_scale = _mm512_slli_epi64::<1>(scale);
        let vb = round_to_odd(v, sh, below);
        let vbl = round_to_odd(_mm512_sub_epi64(v, two_scale), sh, below);
        let vbr = round_to_odd(_mm512_add_epi64(v, two_scale), sh, below);
        let open = _mm512_and_si512(c, one);
        let s = _mm512_srli_epi64::<2>(vb);
        // s / 10 for s < 2^32 (s < 2^28 here).
        let tenth = _mm512_srli_epi64::<35>(_mm512_mul_epu32(s, splat(0xcccc_cccd)));
        let sp10 = _mm512_mul_epu32(tenth, splat(10));
        let tp10 = _mm512_add_epi64(sp10, splat(10));
        let vbl_open = _mm512_add_epi64(vbl, open);
        let upin = _mm512_cmple_epu64_mask(vbl_open, _mm512_slli_epi64::<2>(sp10));
        let wpin =
            _mm512_cmple_epu64_mask(_mm512_add_epi64(_mm512_slli_epi64::<2>(tp10), open), vbr);
        let uin = _mm512_cmple_epu64_mask(vbl_open, _mm512_slli_epi64::<2>(s));
        let t = _mm512_add_epi64(s, one);
        let win = _mm512_cmple_epu64_mask(_mm512_add_epi64(_mm512_slli_epi64::<2>(t), open), vbr);
        let midpoint = _mm512_add_epi64(_mm512_slli_epi64::<2>(s), splat(2));
        let tie = !(upin ^ wpin) & !(uin ^ win) & _mm512_cmpeq_epi64_mask(vb, midpoint);
        let up = (uin ^ win) & win | !(uin ^ win) & _mm512_cmpgt_epu64_mask(vb, midpoint);
        let longer = _mm512_mask_add_epi64(s, up, s, one);
        let shorter = _mm512_mask_blend_epi64(upin, tp10, sp10);
        let d = _mm512_mask_blend_epi64(upin ^ wpin, longer, shorter);
        let d = _mm512_mask_blend_epi64(whole, d, _mm512_srlv_epi64(c, shift));
        let e = _mm512_maskz_mov_epi64(!whole, k);
        // d < 2^28: its first digit d / 10^8 (exact below 2^32) and the 8 others in byte lanes,
        // as the scalar `digits8` splits them.
        let first = _mm512_srli_epi64::<57>(_mm512_mul_epu32(d, splat(1_441_151_881)));
        let rest = _mm512_sub_epi64(d, _mm512_mul_epu32(first, splat(100_000_000)));
        let eight = digits8(rest);
        // The 9 digit bytes: a (digits 1–8), b (digit 9).
        let a = _mm512_or_si512(first, _mm512_slli_epi64::<8>(eight));
        let b = _mm512_srli_epi64::<56>(eight);
        // Leading zero digits: a's zero bytes from the low end, 8 when a is 0 (d is then b).
        let lowest = _mm512_and_si512(a, _mm512_sub_epi64(zero, a));
        let leading_bits = _mm512_and_si512(
            _mm512_sub_epi64(splat(63), _mm512_lzcnt_epi64(lowest)),
            splat(!7),
        );
        let leading_bits =
            _mm512_mask_blend_epi64(_mm512_cmpeq_epi64_mask(a, zero), leading_bits, splat(64));
        let n = _mm512_sub_epi64(splat(9), _mm512_srli_epi64::<3>(leading_bits));
        let low = _mm512_or_si512(
            _mm512_srlv_epi64(a, leading_bits),
            _mm512_sllv_epi64(b, _mm512_sub_epi64(splat(64), leading_bits)),
        );
        let high = _mm512_srlv_epi64(b, leading_bits);
        // Trailing zero digits: none if b is not 0, else 1 and a's zero bytes from the high
        // end (a is not 0 then, d ≥ 1); whole numbers keep theirs.
        let trailing = _mm512_maskz_mov_epi64(
            _mm512_cmpeq_epi64_mask(b, zero) & !whole,
            _mm512_add_epi64(one, _mm512_srli_epi64::<3>(_mm512_lzcnt_epi64(a))),
        );
        out.scalar |= u32::from(outside | tie & !whole) << at;
        let low = _mm512_or_si512(low, splat(ZEROS8));
        let high = _mm512_or_si512(high, splat(ZEROS8));
        let (n, e) = (_mm512_sub_epi64(n, trailing), _mm512_add_epi64(e, trailing));
        // SAFETY: each store writes the 64 bytes of 8 lanes.
        unsafe {
            _mm512_storeu_si512(out.low[at..at + 8].as_mut_ptr().cast(), low);
            _mm512_storeu_si512(out.high[at..at + 8].as_mut_ptr().cast(), high);
            _mm512_storeu_si512(out.digits[at..at + 8].as_mut_ptr().cast(), n);
            _mm512_storeu_si512(out.exponent[at..at + 8].as_mut_ptr().cast(), e);
        }
    }
}
