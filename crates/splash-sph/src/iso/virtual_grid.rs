//! The virtual grid (Sec. III-B): uniform cubic cells of edge `cell` anchored at the origin,
//! known only by that edge; a cell (i, j, k) spans [i, i+1]·cell × …, its corner c at
//! (i, j, k) + `corner_offset(c)`. Cells are materialised only as seeds or when visited.

use glam::{IVec3, Vec3};

use crate::error::Result;

/// Cell indices stay within ±2³⁰ so that neighbours and corners never overflow i32.
const MAX_INDEX: f64 = (1u64 << 30) as f64;

#[derive(Debug, Clone, Copy)]
pub(crate) struct VirtualGrid {
    pub cell: f64,
}

impl VirtualGrid {
    /// The grid of edge `cell` over particles in `[lo, hi]` widened by `reach`; refuses a box
    /// whose cell indices would not fit.
    pub fn new(cell: f32, lo: Vec3, hi: Vec3, reach: f32) -> Result<VirtualGrid> {
        let cell = f64::from(cell);
        let far = (lo.abs().max(hi.abs()).max_element() + reach) as f64 / cell;
        if far.is_nan() || far >= MAX_INDEX {
            bail_limit!(
                "the particles reach {} from the origin, {far:.3e} virtual cells of {}; at most \
                 {MAX_INDEX:.0} fit (a particle far from the fluid?)",
                crate::error::figure(lo.abs().max(hi.abs()).max_element()),
                crate::error::figure(cell as f32)
            );
        }
        Ok(VirtualGrid { cell })
    }

    /// The position of grid node (corner) `n`.
    #[inline]
    pub fn node(&self, n: IVec3) -> Vec3 {
        (n.as_dvec3() * self.cell).as_vec3()
    }
}
