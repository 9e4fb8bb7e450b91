//! Numbers as text for the text mesh formats: an `f32` byte for byte as Rust's `{}` prints it
//! (the shortest decimal that reads back as the same `f32`, never in exponent form), from
//! Żmij's shortest digits (Zverovich 2025) at a fraction of `fmt`'s cost; integers by `itoa`.

use std::fmt::Write as _;

/// Appends `values` as [`push_f32`] prints them, `separator` between them.
pub(crate) fn push_f32s(
    out: &mut Vec<u8>,
    values: impl IntoIterator<Item = f32>,
    separator: &[u8],
) {
    for (k, x) in values.into_iter().enumerate() {
        if k > 0 {
            out.extend_from_slice(separator);
        }
        push_f32(out, x);
    }
}

/// Appends `x` as `format!("{x}")` would.
///
/// Żmij and `fmt` pick the same shortest digits but for one case: when the two nearest
/// shortest candidates are exactly equally far from `x`, Żmij rounds to even and `fmt` up.
/// Such ties need `x`'s exact decimal expansion to be at most one digit longer than the
/// shortest (at most 10 digits), which only the few floats of [`tie_possible`] have; those are
/// printed by `fmt` itself.
pub(crate) fn push_f32(out: &mut Vec<u8>, x: f32) {
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

/// Appends `values` in decimal, `separator` between them.
pub(crate) fn push_ints(out: &mut Vec<u8>, values: [u32; 3], separator: &[u8]) {
    for (k, i) in values.into_iter().enumerate() {
        if k > 0 {
            out.extend_from_slice(separator);
        }
        push_int(out, i);
    }
}

/// Appends `i` in decimal.
#[inline]
pub(crate) fn push_int(out: &mut Vec<u8>, i: impl itoa::Integer) {
    out.extend_from_slice(itoa::Buffer::new().format(i).as_bytes());
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

    #[test]
    fn integers_print_in_decimal() {
        let mut out = Vec::new();
        for i in [0u32, 7, 10, 4_294_967_295] {
            push_int(&mut out, i);
            out.push(b' ');
        }
        assert_eq!(out, b"0 7 10 4294967295 ");
    }
}
