//! The cubic spline kernel of SPH (Monaghan 1992; Müller et al. 2003 use it for the colour field)
//! in q = d/h, the shape shared by the density and anisotropic fields and by the attribute kernel.

use crate::neighbours::lane::Lane;

/// Cubic spline with q = d/h over its compact support h, without the factor 8/(π h³):
/// 6q³ − 6q² + 1 up to q = ½, 2(1 − q)³ up to 1, written as 2(1 − q)₊³ − 8(½ − q)₊³ so that
/// it has no branch.
#[inline(always)]
pub(super) fn cubic_spline<L: Lane>(q: L) -> L {
    let (a, b) = clamped(q);
    L::splat(2.0) * a * a * a - L::splat(8.0) * b * b * b
}

/// d/dq of [`cubic_spline`], divided by q (finite at q = 0, where the slope is 0).
#[inline(always)]
pub(super) fn cubic_spline_slope_over_q<L: Lane>(q: L) -> L {
    let (a, b) = clamped(q);
    (L::splat(24.0) * b * b - L::splat(6.0) * a * a) / q.max(L::splat(f32::MIN_POSITIVE))
}

/// (1 − q)₊ and (½ − q)₊.
#[inline(always)]
fn clamped<L: Lane>(q: L) -> (L, L) {
    let zero = L::splat(0.0);
    ((L::splat(1.0) - q).max(zero), (L::splat(0.5) - q).max(zero))
}
