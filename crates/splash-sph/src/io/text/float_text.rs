//! Numbers as text for the text mesh formats: an `f32` byte for byte as Rust's `{}` prints it
//! (the shortest decimal that reads back as the same `f32`, never in exponent form), by
//! Schubfach (Giulietti 2020, exact in 64- or 128-bit integers over the range meshes use) or
//! else from Żmij's shortest digits (Zverovich 2025), at a fraction of `fmt`'s cost; integers
//! likewise.
//!
//! Each number is composed in registers and stored with fixed-size stores into reserved spare
//! capacity (the bytes past the number's end are overwritten by the next one), a row of three
//! at a time: copies of a variable length are calls to `memmove`, which cost as much as the
//! digits, and each reservation is a capacity check and a length update.

use std::fmt::Write as _;
use std::hint::select_unpredictable;

use super::decimal_lanes::{self, BLOCK, Decimals, Integers, POW5};

/// Appends `prefix`, `values` as [`push_f32`] prints them with `separator` between them,
/// and `end`: a row composed in one reservation of spare capacity and appended at once,
/// unless one of the values is outside [`schubfach`]'s range.
#[inline]
pub(crate) fn push_f32_row<const P: usize, const S: usize, const E: usize>(
    out: &mut Vec<u8>,
    prefix: &[u8; P],
    values: [f32; 3],
    separator: &[u8; S],
    end: &[u8; E],
) {
    let mut spare = Spare::of(out);
    let mut at = spare.put(0, prefix);
    for (k, x) in values.into_iter().enumerate() {
        if k > 0 {
            at = spare.put(at, separator);
        }
        match schubfach(&mut spare, at, x) {
            Some(end) => at = end,
            None => return push_f32_row_slowly(out, prefix, values, separator, end),
        }
    }
    at = spare.put(at, end);
    spare.commit(at);
}

/// A slice of floats printed as [`push_f32_row`] prints them, in rows of three taken in
/// order: their shortest digits are found eight at a time in AVX-512 lanes
/// ([`decimal_lanes`]) where the CPU has them, ahead of their placement, else by [`schubfach`].
pub(crate) struct F32Text<'a> {
    values: &'a [f32],
    lanes: bool,
    /// The index of the first value in `decimals`.
    start: usize,
    decimals: Decimals,
}

impl<'a> F32Text<'a> {
    pub(crate) fn new(values: &'a [f32]) -> Self {
        Self::with(values, decimal_lanes::available())
    }

    /// With the lanes or without them (they must be available).
    fn with(values: &'a [f32], lanes: bool) -> Self {
        Self {
            values,
            lanes,
            // Past every value: none is in the lanes yet.
            start: values.len() + BLOCK,
            decimals: Decimals::EMPTY,
        }
    }

    /// [`push_f32_row`] of values `3·row..3·row + 3`.
    #[inline(always)]
    pub(crate) fn push_row<const P: usize, const S: usize, const E: usize>(
        &mut self,
        out: &mut Vec<u8>,
        prefix: &[u8; P],
        row: usize,
        separator: &[u8; S],
        end: &[u8; E],
    ) {
        let first = 3 * row;
        let values: [f32; 3] = self.values[first..first + 3].try_into().expect("3 values");
        if !self.lanes {
            return push_f32_row(out, prefix, values, separator, end);
        }
        let mut spare = Spare::of(out);
        let mut at = spare.put(0, prefix);
        for k in 0..3 {
            if k > 0 {
                at = spare.put(at, separator);
            }
            match self.place(&mut spare, at, first + k) {
                Some(end) => at = end,
                None => return push_f32_row_slowly(out, prefix, values, separator, end),
            }
        }
        at = spare.put(at, end);
        spare.commit(at);
    }

    /// Writes value `j` at `at` as [`schubfach`] does, from the lanes; `None` as it.
    #[inline(always)]
    fn place(&mut self, spare: &mut Spare<'_>, at: usize, j: usize) -> Option<usize> {
        let mut lane = j.wrapping_sub(self.start);
        if lane >= BLOCK {
            self.fill(j);
            lane = 0;
        }
        let x = self.values[j];
        let decimals = &self.decimals;
        if decimals.scalar >> lane & 1 != 0 {
            return schubfach_apart(spare, at, x);
        }
        // The sign, overwritten by the first digit of a positive x.
        spare.put1(at, b'-');
        let at = at + (x.to_bits() >> 31) as usize;
        let text = u128::from(decimals.low[lane]) | u128::from(decimals.high[lane]) << 64;
        let (n, e) = (
            decimals.digits[lane] as usize,
            decimals.exponent[lane] as i32,
        );
        Some(place16(spare, at, text, n, e))
    }

    /// The lanes of values `j..j + BLOCK` (past the end: ones).
    #[inline(never)]
    fn fill(&mut self, j: usize) {
        let block = match self.values.get(j..j + BLOCK) {
            Some(block) => block.try_into().expect("a block"),
            None => {
                let mut block = [1.0; BLOCK];
                let rest = &self.values[j..];
                block[..rest.len()].copy_from_slice(rest);
                block
            }
        };
        decimal_lanes::decimals(&block, &mut self.decimals);
        self.start = j;
    }
}

/// [`schubfach`] as a call, for the values the lanes leave.
#[inline(never)]
fn schubfach_apart(spare: &mut Spare<'_>, at: usize, x: f32) -> Option<usize> {
    schubfach(spare, at, x)
}

/// [`push_f32_row`] one value at a time, for the rare rows with a value outside
/// [`schubfach`]'s range.
#[cold]
fn push_f32_row_slowly(
    out: &mut Vec<u8>,
    prefix: &[u8],
    values: [f32; 3],
    separator: &[u8],
    end: &[u8],
) {
    out.extend_from_slice(prefix);
    for (k, x) in values.into_iter().enumerate() {
        if k > 0 {
            out.extend_from_slice(separator);
        }
        push_f32(out, x);
    }
    out.extend_from_slice(end);
}

/// Appends `x` as `format!("{x}")` would: by [`schubfach`] where it applies (all but a few
/// coordinates of a mesh), else as follows.
///
/// Żmij and `fmt` pick the same shortest digits but for one case: when the two nearest
/// shortest candidates are exactly equally far from `x`, Żmij rounds to even and `fmt` up.
/// Such ties need `x`'s exact decimal expansion to be at most one digit longer than the
/// shortest (at most 10 digits), which only the few floats of [`tie_possible`] have; those are
/// printed by `fmt` itself.
pub(crate) fn push_f32(out: &mut Vec<u8>, x: f32) {
    let mut spare = Spare::of(out);
    if let Some(len) = schubfach(&mut spare, 0, x) {
        spare.commit(len);
        return;
    }
    if tie_possible(x) {
        let mut text = String::with_capacity(48);
        // Writing into a String cannot fail.
        let _ = write!(text, "{x}");
        out.extend_from_slice(text.as_bytes());
        return;
    }
    let mut buffer = zmij::Buffer::new();
    let text = buffer.format(x).as_bytes();
    match text.iter().position(|&b| b == b'e') {
        // Within Żmij's fixed range its text is `fmt`'s, but for whole numbers' ".0".
        None => out.extend_from_slice(text.strip_suffix(b".0").unwrap_or(text)),
        Some(e) => positional(out, &text[..e], &text[e + 1..]),
    }
}

/// Whether `x`'s exact value has at most 10 significant decimal digits, where a tie between two
/// shortest candidates can happen; and every whole number from 2^24 on, where the check would
/// need wide arithmetic (no mesh coordinate is that large). Non-finite values and zero: no.
fn tie_possible(x: f32) -> bool {
    let bits = x.to_bits() & 0x7fff_ffff;
    let biased = (bits >> 23) as i32;
    if biased == 0 || biased == 0xff {
        // Zero and subnormals (whose exact expansions are far longer), infinities and NaN.
        return false;
    }
    // |x| = m * 2^e with m odd.
    let m = (bits & 0x7f_ffff) | 1 << 23;
    let e = biased - 150 + m.trailing_zeros() as i32;
    let m = m >> m.trailing_zeros();
    if e >= 0 {
        // A whole number: below 2^24 its digits are all needed and printed exactly by both.
        return x.abs() >= 16_777_216.0;
    }
    // m * 2^e = m * 5^s / 10^s, whose digits are those of the odd m * 5^s; from s = 15 on,
    // 5^s alone has 11 digits.
    let s = (-e) as u32;
    s <= 14 && u64::from(m) * 5u64.pow(s) < 10_000_000_000
}

/// Appends `mantissa` (`-d.ddd` or `d`) times 10^`exponent` without an exponent, as `fmt` does:
/// `0.000…ddd`, `dd.dd` or `ddd000…`, without trailing zeros after the point.
fn positional(out: &mut Vec<u8>, mantissa: &[u8], exponent: &[u8]) {
    let (negative, mantissa) = match mantissa.split_first() {
        Some((b'-', rest)) => (true, rest),
        _ => (false, mantissa),
    };
    // At most 9 significant digits for an f32.
    let mut digits = [0u8; 24];
    let (mut n, mut point) = (0, None);
    for &b in mantissa.iter().take(digits.len()) {
        if b == b'.' {
            point = Some(n);
        } else {
            digits[n] = b;
            n += 1;
        }
    }
    let (exponent_negative, exponent) = match exponent.split_first() {
        Some((b'-', rest)) => (true, rest),
        Some((b'+', rest)) => (false, rest),
        _ => (false, exponent),
    };
    let magnitude = exponent
        .iter()
        .fold(0i32, |e, &d| e * 10 + i32::from(d - b'0'));
    // Digits before the decimal point.
    let mut before = point.unwrap_or(n) as i32
        + if exponent_negative {
            -magnitude
        } else {
            magnitude
        };
    let mut first = 0;
    while first < n && digits[first] == b'0' {
        first += 1;
        before -= 1;
    }
    while n > first && digits[n - 1] == b'0' {
        n -= 1;
    }
    let digits = &digits[first..n];
    if negative {
        out.push(b'-');
    }
    let len = digits.len() as i32;
    if digits.is_empty() {
        out.push(b'0');
    } else if before <= 0 {
        out.extend_from_slice(b"0.");
        out.extend(std::iter::repeat_n(b'0', before.unsigned_abs() as usize));
        out.extend_from_slice(digits);
    } else if before < len {
        out.extend_from_slice(&digits[..before as usize]);
        out.push(b'.');
        out.extend_from_slice(&digits[before as usize..]);
    } else {
        out.extend_from_slice(digits);
        out.extend(std::iter::repeat_n(b'0', (before - len) as usize));
    }
}

/// Appends `prefix`, `values` in decimal with `separator` between them, each as `a` or,
/// given an `infix`, as `a{infix}a` (an OBJ face corner `a//a`, whose vertex and normal
/// indices are one), and `end`: a row composed in one reservation of spare capacity.
#[inline]
pub(crate) fn push_int_row<const P: usize, const S: usize, const E: usize>(
    out: &mut Vec<u8>,
    prefix: &[u8; P],
    values: [u64; 3],
    separator: &[u8; S],
    infix: Option<&[u8; 2]>,
    end: &[u8; E],
) {
    if values.iter().any(|&v| v >= 100_000_000) {
        return push_int_row_slowly(out, prefix, values, separator, infix, end);
    }
    let mut spare = Spare::of(out);
    let mut at = spare.put(0, prefix);
    for (k, v) in values.into_iter().enumerate() {
        if k > 0 {
            at = spare.put(at, separator);
        }
        let (text, n, _) = digits8_text(v);
        spare.put8(at, text);
        at += n;
        if let Some(infix) = infix {
            at = spare.put(at, infix);
            spare.put8(at, text);
            at += n;
        }
    }
    at = spare.put(at, end);
    spare.commit(at);
}

/// A slice of integers, each plus an offset, printed as [`push_int_row`] prints them, in
/// rows of three taken in order: their digits are found eight at a time in AVX-512 lanes
/// ([`decimal_lanes`]) where the CPU has them, else as [`push_int_row`] does.
pub(crate) struct IntText<'a> {
    values: &'a [u32],
    offset: u32,
    lanes: bool,
    /// The index of the first value in `integers`.
    start: usize,
    integers: Integers,
}

impl<'a> IntText<'a> {
    pub(crate) fn new(values: &'a [u32], offset: u32) -> Self {
        Self::with(values, offset, decimal_lanes::available())
    }

    /// With the lanes or without them (they must be available).
    fn with(values: &'a [u32], offset: u32, lanes: bool) -> Self {
        Self {
            values,
            offset,
            lanes,
            // Past every value: none is in the lanes yet.
            start: values.len() + BLOCK,
            integers: Integers::EMPTY,
        }
    }

    /// [`push_int_row`] of values `3·row..3·row + 3`, each plus the offset.
    #[inline(always)]
    pub(crate) fn push_row<const P: usize, const S: usize, const E: usize>(
        &mut self,
        out: &mut Vec<u8>,
        prefix: &[u8; P],
        row: usize,
        separator: &[u8; S],
        infix: Option<&[u8; 2]>,
        end: &[u8; E],
    ) {
        let first = 3 * row;
        let values: [u32; 3] = self.values[first..first + 3].try_into().expect("3 values");
        let values = values.map(|v| u64::from(v) + u64::from(self.offset));
        if !self.lanes {
            return push_int_row(out, prefix, values, separator, infix, end);
        }
        let mut spare = Spare::of(out);
        let mut at = spare.put(0, prefix);
        for k in 0..3 {
            if k > 0 {
                at = spare.put(at, separator);
            }
            let lane = self.lane(first + k);
            if self.integers.scalar >> lane & 1 != 0 {
                return push_int_row_slowly(out, prefix, values, separator, infix, end);
            }
            let (text, n) = (
                self.integers.text[lane],
                self.integers.digits[lane] as usize,
            );
            spare.put8(at, text);
            at += n;
            if let Some(infix) = infix {
                at = spare.put(at, infix);
                spare.put8(at, text);
                at += n;
            }
        }
        at = spare.put(at, end);
        spare.commit(at);
    }

    /// The lane of value `j`, filled with values `j..j + BLOCK` unless it holds `j` already.
    #[inline(always)]
    fn lane(&mut self, j: usize) -> usize {
        let lane = j.wrapping_sub(self.start);
        if lane < BLOCK {
            return lane;
        }
        self.fill(j);
        0
    }

    /// The lanes of values `j..j + BLOCK` (past the end: zeros).
    #[inline(never)]
    fn fill(&mut self, j: usize) {
        let block = match self.values.get(j..j + BLOCK) {
            Some(block) => block.try_into().expect("a block"),
            None => {
                let mut block = [0; BLOCK];
                let rest = &self.values[j..];
                block[..rest.len()].copy_from_slice(rest);
                block
            }
        };
        decimal_lanes::integers(&block, self.offset, &mut self.integers);
        self.start = j;
    }
}

/// [`push_int_row`] by `itoa`, for indices of 9 digits or more (meshes of 10^8 vertices).
#[cold]
fn push_int_row_slowly(
    out: &mut Vec<u8>,
    prefix: &[u8],
    values: [u64; 3],
    separator: &[u8],
    infix: Option<&[u8; 2]>,
    end: &[u8],
) {
    out.extend_from_slice(prefix);
    for (k, v) in values.into_iter().enumerate() {
        if k > 0 {
            out.extend_from_slice(separator);
        }
        let mut text = itoa::Buffer::new();
        let text = text.format(v).as_bytes();
        out.extend_from_slice(text);
        if let Some(infix) = infix {
            out.extend_from_slice(infix);
            out.extend_from_slice(text);
        }
    }
    out.extend_from_slice(end);
}

/// Sixteen `'0'`s, as the bytes of a little-endian `u128`.
const ZEROS: u128 = u128::from_le_bytes([b'0'; 16]);

/// The decimal digits of `v` from 1 to 10^9 − 1 as the bytes of a little-endian `u128` (the
/// first digit in the lowest byte), followed by `'0'`s; their count; and how many of them are
/// trailing zeros.
#[inline]
fn digits9_trailing(v: u64) -> (u128, usize, usize) {
    debug_assert!((1..1_000_000_000).contains(&v));
    let raw = u128::from(v / 100_000_000) | u128::from(digits8(v % 100_000_000)) << 8;
    let leading = (raw.trailing_zeros() / 8) as usize;
    let trailing = ((raw << 56).leading_zeros() / 8) as usize;
    ((raw >> (8 * leading)) | ZEROS, 9 - leading, trailing)
}

/// Eight `'0'`s, as the bytes of a little-endian `u64`.
const ZEROS8: u64 = u64::from_le_bytes([b'0'; 8]);

/// The decimal digits of `v` < 10^8 as the bytes of a little-endian `u64` (the first digit in
/// the lowest byte), followed by `'0'`s; their count; and how many of them are trailing zeros
/// (for `v` ≥ 1).
#[inline(always)]
fn digits8_text(v: u64) -> (u64, usize, usize) {
    debug_assert!(v < 100_000_000);
    let raw = digits8(v);
    // Leading zero digits are the zero bytes at the low end, trailing ones at the high end.
    let leading = ((raw.trailing_zeros() / 8) as usize).min(7);
    let trailing = (raw.leading_zeros() / 8) as usize;
    ((raw >> (8 * leading)) | ZEROS8, 8 - leading, trailing)
}

/// The 8 decimal digits of `v` < 10^8, leading zeros included, as byte values 0–9 of a
/// little-endian `u64`, the first digit in the lowest byte. Computed in registers, by
/// splitting into 4, 2 and 1 digit lanes: digits stored byte by byte and read back as one
/// word would stall on the store-to-load forwarding.
#[inline]
fn digits8(v: u64) -> u64 {
    // Two 4-digit lanes of 32 bits: the first four digits in the low lane.
    let y = (v / 10_000) | ((v % 10_000) << 32);
    // Two-digit lanes of 16 bits: ⌊y/100⌋ as y·10486 >> 20, exact below 10^4.
    let high = ((y * 10_486) >> 20) & 0x0000_007f_0000_007f;
    let y = high | (y - high * 100) << 16;
    // One-digit lanes of 8 bits: ⌊y/10⌋ as y·103 >> 10, exact below 100.
    let high = ((y * 103) >> 10) & 0x000f_000f_000f_000f;
    high | (y - high * 10) << 8
}

/// Bytes a [`Spare`] reserves: a row of three numbers, its separators and stores' overhang.
const SPARE: usize = 128;

/// The [`SPARE`] bytes of spare capacity reserved at the end of a `Vec`, written by fixed-size stores
/// (a store past the number's end is harmless: the next number overwrites it) and committed.
/// They are reached through a pointer taken once, in a register: through the `Vec` each store
/// reloaded its fields (a byte store may alias them).
struct Spare<'a> {
    out: &'a mut Vec<u8>,
    bytes: *mut u8,
}

impl<'a> Spare<'a> {
    #[inline]
    fn of(out: &'a mut Vec<u8>) -> Self {
        out.reserve(SPARE);
        let bytes = out.spare_capacity_mut()[..SPARE].as_mut_ptr().cast();
        Self { out, bytes }
    }

    /// Writes `bytes` at `at`; returns where they end.
    #[inline]
    fn put<const N: usize>(&mut self, at: usize, bytes: &[u8; N]) -> usize {
        assert!(at + N <= SPARE, "within the reserved bytes");
        // SAFETY: `self.bytes` points to SPARE bytes of `self.out`'s capacity, which `self`
        // borrows; the bytes written lie within them (asserted).
        unsafe { self.bytes.add(at).cast::<[u8; N]>().write_unaligned(*bytes) };
        at + N
    }

    #[inline]
    fn put1(&mut self, at: usize, byte: u8) {
        self.put(at, &[byte]);
    }

    #[inline]
    fn put8(&mut self, at: usize, word: u64) {
        self.put(at, &word.to_le_bytes());
    }

    #[inline]
    fn put16(&mut self, at: usize, word: u128) {
        self.put(at, &word.to_le_bytes());
    }

    /// Appends the first `len` bytes written.
    #[inline]
    fn commit(self, len: usize) {
        assert!(len <= SPARE);
        // SAFETY: the caller wrote the first `len` bytes of the spare capacity.
        unsafe { self.out.set_len(self.out.len() + len) };
    }
}

/// Powers of ten up to 10^19, the largest below 2^64.
const POW10: [u64; 20] = {
    let mut p = [1u64; 20];
    let mut k = 1;
    while k < 20 {
        p[k] = p[k - 1] * 10;
        k += 1;
    }
    p
};

/// Writes `x` as `{}` prints it at `at` in `spare` and returns where it ends, if `x` is a
/// normal float of 2^-40 ≤ |x| < 2^24 whose significand is not a power of two (those have an
/// uneven rounding interval) and whose two nearest shortest candidates are not equally near
/// (where `fmt` and Schubfach round differently); else returns `None`, `spare` unchanged.
/// At most 24 bytes, with stores reaching 31 bytes past `at`.
///
/// Schubfach (Giulietti 2020, "The Schubfach way to render doubles", sections 8–9): with
/// x = c·2^q, k = ⌊q·log10 2⌋ and the rounding interval's bounds and x scaled by 4·10^−k (so
/// that the interval is 1 to 10 units wide), the shortest decimal is the one multiple of 10
/// in the interval if there is one, else the nearer of the two integers around x. Here the
/// scaling is exact: 10^−k ≤ 10^19 and c < 2^24 fit 128 bits, and a value's fraction below
/// the units survives as a sticky low bit (round to odd), which keeps every comparison exact.
#[inline(always)]
fn schubfach(spare: &mut Spare<'_>, at: usize, x: f32) -> Option<usize> {
    let bits = x.to_bits();
    let biased = (bits >> 23) & 0xff;
    let fraction = bits & 0x7f_ffff;
    // |x| = c·2^−shift.
    let shift = 150 - biased as i32;
    if fraction == 0 || !(1..=63).contains(&shift) {
        return None;
    }
    let c = u64::from(fraction | 1 << 23);
    let shift = shift as u32;
    // |x| = d·10^e, d < 2^24·10 < 10^9 (s below is under c·10).
    let whole = shift <= 23 && c & ((1 << shift) - 1) == 0;
    let (d, e) = if whole {
        // A whole number, printed whole.
        (c >> shift, 0)
    } else {
        // k = ⌊−shift·log10 2⌋, from −19 to −1.
        let k = ((-i64::from(shift) * 661_971_961_083) >> 41) as i32;
        let (vb, vbl, vbr) = scaled(c, shift, k);
        // Bounds are in the interval for an even c, out for an odd one.
        let open = c & 1;
        let s = vb >> 2;
        let sp10 = s / 10 * 10;
        let tp10 = sp10 + 10;
        let upin = vbl + open <= sp10 << 2;
        let wpin = (tp10 << 2) + open <= vbr;
        let t = s + 1;
        let uin = vbl + open <= s << 2;
        let win = (t << 2) + open <= vbr;
        let midpoint = (s << 2) + 2;
        // One branch, rarely taken (`&`, not `&&`).
        if (upin == wpin) & (uin == win) & (vb == midpoint) {
            // A tie: `fmt` rounds up, Schubfach to even; left to `fmt`.
            return None;
        }
        // Selected without branches: which applies varies from one coordinate to the next
        // (grid-aligned or interpolated), and a mispredicted branch costs as much as the
        // digits. The trailing zeros are dropped from the digits below.
        let longer = s + u64::from(select_unpredictable(uin != win, win, vb > midpoint));
        let shorter = select_unpredictable(upin, sp10, tp10);
        (select_unpredictable(upin != wpin, shorter, longer), k)
    };
    // The sign, overwritten by the first digit of a positive x.
    spare.put1(at, b'-');
    let at = at + (bits >> 31) as usize;
    // Whole numbers keep their zeros (e stays 0); the others lose theirs.
    let keep = |trailing| if whole { 0 } else { trailing };
    Some(if d < 100_000_000 {
        let (text, n, trailing) = digits8_text(d);
        let trailing = keep(trailing);
        place8(spare, at, text, n - trailing, e + trailing as i32)
    } else {
        let (text, n, trailing) = digits9_trailing(d);
        let trailing = keep(trailing);
        place16(spare, at, text, n - trailing, e + trailing as i32)
    })
}

/// 4c·10^k and the rounding interval's bounds 4c ± 2 times 10^k, divided by 2^shift and
/// rounded to odd: `(vb, vbl, vbr)`. In 64 bits where 10^k = 5^k·2^k makes them fit (|x| ≥
/// 2^−30, all coordinates but the tiniest), else in 128.
#[inline(always)]
fn scaled(c: u64, shift: u32, k: i32) -> (u64, u64, u64) {
    if k >= -15 {
        // 4c·5^−k < 2^26·5^15 < 2^61; shift + k from 0 to 53.
        let scale = POW5[(-k) as usize];
        let shift = (shift as i32 + k) as u32;
        let round_to_odd = |v: u64| v >> shift | u64::from(v & ((1 << shift) - 1) != 0);
        let v = (c << 2) * scale;
        return (
            round_to_odd(v),
            round_to_odd(v - 2 * scale),
            round_to_odd(v + 2 * scale),
        );
    }
    let scale = u128::from(POW10[(-k) as usize]);
    // ⌊v / 2^shift⌋ with a sticky low bit; shift < 64.
    let round_to_odd = |v: u128| {
        let (high, low) = ((v >> 64) as u64, v as u64);
        let floor = high << (64 - shift) | low >> shift;
        floor | u64::from(low & ((1 << shift) - 1) != 0)
    };
    let v = u128::from(c << 2) * scale;
    (
        round_to_odd(v),
        round_to_odd(v - 2 * scale),
        round_to_odd(v + 2 * scale),
    )
}

/// Writes d·10^e positionally at `at`, d's `n` ≤ 8 digits in `text` ([`digits8_text`]), d
/// without trailing zeros unless e = 0; returns the end.
#[inline(always)]
fn place8(spare: &mut Spare<'_>, at: usize, text: u64, n: usize, e: i32) -> usize {
    // Digits before the decimal point.
    let before = n as i32 + e;
    if e >= 0 {
        // Whole: the digits, then e zeros (the text's '0's past its digits); x < 2^24 has at
        // most 8 digits.
        spare.put8(at, text);
        at + before as usize
    } else if before > 0 {
        // dd.dd: the digits, the point over the first digit after it, the rest after it.
        let b = before as usize;
        spare.put8(at, text);
        spare.put1(at + b, b'.');
        spare.put8(at + b + 1, text >> (8 * b));
        at + n + 1
    } else {
        // 0.000ddd: at most 12 zeros after the point for x ≥ 2^−40.
        let zeros = (-before) as usize;
        spare.put8(at, ZEROS8 & !(0xff << 8) | u64::from(b'.') << 8);
        spare.put8(at + 8, ZEROS8);
        spare.put8(at + 2 + zeros, text);
        at + 2 + zeros + n
    }
}

/// [`place8`] for d of 9 digits, in `text` as [`digits9_trailing`] gives them.
#[inline(always)]
fn place16(spare: &mut Spare<'_>, at: usize, text: u128, n: usize, e: i32) -> usize {
    let before = n as i32 + e;
    if e >= 0 {
        spare.put16(at, text);
        at + before as usize
    } else if before > 0 {
        let b = 8 * before as u32;
        let point = (text & ((1 << b) - 1)) | u128::from(b'.') << b | (text >> b) << (b + 8);
        spare.put16(at, point);
        at + n + 1
    } else {
        let zeros = (-before) as usize;
        spare.put16(at, ZEROS & !(0xff << 8) | u128::from(b'.') << 8);
        spare.put16(at + 2 + zeros, text);
        at + 2 + zeros + n
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(x: f32) {
        let mut ours = Vec::new();
        push_f32(&mut ours, x);
        let std = format!("{x}");
        assert_eq!(
            String::from_utf8(ours).unwrap(),
            std,
            "bits {:#010x}",
            x.to_bits()
        );
    }

    /// Every 65521st bit pattern (both signs, every exponent, subnormals, NaNs) and the
    /// patterns around the edges: ties (2.19140625, 2097398.25), whole numbers near 2^24, the
    /// extremes, zeros. The whole f32 range was checked this way once (4 294 967 296 values).
    #[test]
    fn floats_print_as_fmt_prints_them() {
        for bits in (0..=u32::MAX).step_by(65_521) {
            check(f32::from_bits(bits));
        }
        let edges = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.5,
            2.191_406_3,
            2_097_398.3,
            16_777_215.0,
            16_777_216.0,
            16_777_218.0,
            1.0e7,
            1.0e-7,
            1.5e-5,
            123_456_790.0,
            f32::MAX,
            f32::MIN,
            f32::MIN_POSITIVE,
            f32::EPSILON,
            f32::from_bits(1),
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        for x in edges {
            for bits in x.to_bits().saturating_sub(3)..=x.to_bits().saturating_add(3) {
                check(f32::from_bits(bits));
            }
        }
    }

    /// Schubfach's range (2^-40 ≤ |x| < 2^24) densely: every 997th bit pattern, both signs.
    /// Every float of the range was checked this way once.
    #[test]
    fn schubfach_prints_as_fmt_prints() {
        for bits in (0x2b80_0000u32..0x4b80_0000).step_by(997) {
            check(f32::from_bits(bits));
            check(-f32::from_bits(bits));
        }
    }

    /// 3 million pseudo-random bit patterns (every exponent, both signs, subnormals, NaNs), so
    /// that a row mixes the fast path with the fallbacks; decimal grids as a mesh's
    /// coordinates are (i·0.007, i·10^−j); and the powers of ten from 10^−12 to 10^8 with their
    /// neighbours.
    fn assorted() -> Vec<f32> {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut random = || {
            // xorshift64*
            state ^= state >> 12;
            state ^= state << 25;
            state ^= state >> 27;
            (state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 32) as u32
        };
        let mut values: Vec<f32> = (0..3_000_000).map(|_| f32::from_bits(random())).collect();
        for i in -20_000..20_000 {
            values.push(i as f32 * 0.007);
            for j in 1..12 {
                values.push(i as f32 / 10f32.powi(j));
            }
        }
        for j in -12..=8 {
            let p = 10f32.powi(j);
            for bits in p.to_bits() - 3..=p.to_bits() + 3 {
                values.extend([f32::from_bits(bits), -f32::from_bits(bits)]);
            }
        }
        values
    }

    /// Asserts that `ours` holds the rows of three of `values` as `format!` prints them.
    fn assert_rows(ours: Vec<u8>, values: &[f32]) {
        let ours = String::from_utf8(ours).unwrap();
        let mut lines = ours.lines();
        for row in values.chunks_exact(3) {
            let [x, y, z] = [row[0], row[1], row[2]];
            assert_eq!(lines.next(), Some(format!("<{x}, {y}, {z}>").as_str()));
        }
        assert_eq!(lines.next(), None);
    }

    /// Rows of three as `push_f32_row` writes them against `format!`.
    #[test]
    fn rows_print_as_fmt_prints() {
        let values = assorted();
        let mut ours = Vec::new();
        for row in values.chunks_exact(3) {
            push_f32_row(&mut ours, b"<", [row[0], row[1], row[2]], b", ", b">\n");
        }
        assert_rows(ours, &values);
    }

    /// `F32Text`'s rows with the lanes and without them against `format!`: the assorted values
    /// and Schubfach's range (2^-40 ≤ |x| < 2^24, every 997th bit pattern, both signs), whose
    /// lanes the scalar path fills where the lanes leave them; started at each offset into
    /// their blocks of eight, and ended inside one.
    #[test]
    fn lanes_print_as_fmt_prints() {
        let mut values = assorted();
        for bits in (0x2b80_0000u32..0x4b80_0000).step_by(997) {
            values.extend([f32::from_bits(bits), -f32::from_bits(bits)]);
        }
        values.truncate(values.len() / 3 * 3 - 3);
        let mut paths = vec![false];
        if decimal_lanes::available() {
            paths.push(true);
        } else {
            println!("skipped the lanes: this CPU lacks AVX-512 F, DQ, CD or BW");
        }
        for lanes in paths {
            for skip in 0..3 {
                let values = &values[3 * skip..];
                let mut text = F32Text::with(values, lanes);
                let mut ours = Vec::new();
                for row in 0..values.len() / 3 {
                    text.push_row(&mut ours, b"<", row, b", ", b">\n");
                }
                assert_rows(ours, values);
            }
        }
    }

    /// Every 13th float the lanes print themselves (2^-26 ≤ x < 2^24, and the negative of
    /// every 61st of those) through the lanes and through the scalar path, on all threads: the
    /// same bytes. Every float of that range was checked this way once (step 1: 402 M floats).
    #[test]
    fn lanes_print_every_float_as_the_scalar_path() {
        use rayon::prelude::*;
        if !decimal_lanes::available() {
            println!("skipped: this CPU lacks AVX-512 F, DQ, CD or BW");
            return;
        }
        let (first, last) = (0x3280_0000u32, 0x4b80_0000u32);
        let step = 3 << 16;
        (first..last)
            .into_par_iter()
            .step_by(step)
            .for_each(|start| {
                let mut values: Vec<f32> = (start..(start + step as u32).min(last))
                    .step_by(13)
                    .map(f32::from_bits)
                    .collect();
                values.extend(values.iter().step_by(61).map(|x| -x).collect::<Vec<f32>>());
                values.truncate(values.len() / 3 * 3);
                let mut text = F32Text::with(&values, true);
                let (mut lanes, mut scalar) = (Vec::new(), Vec::new());
                for (row, v) in values.chunks_exact(3).enumerate() {
                    text.push_row(&mut lanes, b"", row, b" ", b"\n");
                    push_f32_row(&mut scalar, b"", [v[0], v[1], v[2]], b" ", b"\n");
                }
                assert!(lanes == scalar, "from bits {start:#x}");
            });
    }

    /// `IntText`'s rows with the lanes and without them, offsets 0 and 1, against `format!`:
    /// every width from 1 to 10 digits and its edges (10^8 − 1 + 1 is the first the lanes
    /// leave), u32::MAX, and 300 000 pseudo-random integers of every width.
    #[test]
    fn integer_lanes_print_in_decimal() {
        let mut values = vec![0u32, 1, u32::MAX, u32::MAX - 1];
        for k in 1..10 {
            let p = 10u32.pow(k);
            values.extend([p - 2, p - 1, p, p + 7]);
        }
        let mut state = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..300_000 {
            state ^= state >> 12;
            state ^= state << 25;
            state ^= state >> 27;
            let random = state.wrapping_mul(0x2545_f491_4f6c_dd1d);
            // A random width: every count of digits about equally often.
            values.push((random >> 32) as u32 >> (random % 32));
        }
        values.truncate(values.len() / 3 * 3);
        let mut paths = vec![false];
        if decimal_lanes::available() {
            paths.push(true);
        } else {
            println!("skipped the lanes: this CPU lacks AVX-512 F, DQ, CD or BW");
        }
        for lanes in paths {
            for offset in [0, 1] {
                let mut text = IntText::with(&values, offset, lanes);
                let (mut ours, mut expected) = (Vec::new(), String::new());
                for (row, v) in values.chunks_exact(3).enumerate() {
                    let [a, b, c] = [v[0], v[1], v[2]].map(|v| u64::from(v) + u64::from(offset));
                    text.push_row(&mut ours, b"f ", row, b" ", Some(b"//"), b"\n");
                    expected += &format!("f {a}//{a} {b}//{b} {c}//{c}\n");
                }
                assert_eq!(String::from_utf8(ours).unwrap(), expected, "lanes {lanes}");
            }
        }
    }

    /// Every width from 1 to 20 digits and the edges of each, in rows of three that mix the
    /// widths (and so the fast and slow paths), alone (`a,b,c`) and twice (`a//a`).
    #[test]
    fn integers_print_in_decimal() {
        let mut values = vec![0u64, u64::MAX, 4_294_967_295];
        for k in 1..20 {
            let p = 10u64.pow(k);
            values.extend([p - 1, p, p + 7]);
        }
        let (mut ours, mut expected) = (Vec::new(), String::new());
        for w in values.windows(3) {
            let [a, b, c] = [w[0], w[1], w[2]];
            push_int_row(&mut ours, b"f ", [a, b, c], b" ", Some(b"//"), b"\n");
            push_int_row(&mut ours, b"<", [c, a, b], b",", None, b">\n");
            expected += &format!("f {a}//{a} {b}//{b} {c}//{c}\n<{c},{a},{b}>\n");
        }
        assert_eq!(String::from_utf8(ours).unwrap(), expected);
    }
}
