//! Piecewise-polynomial metaballs, c·(1 − d²/R_c²)^α within the cut-off radius R_c: the
//! family of Gourmel et al. 2010 (c = 1), which includes the kernel of Triquet et al. used by
//! Rosenberg & Birdwell 2008, (d/√2R_c)⁴ − (d/√2R_c)² + 1/4 = (1 − d²/R_c²)²/4 (α = 2, c = 1/4).

use crate::error::Result;
use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::radial_kernel::RadialKernel;
use super::scalar_field::ScalarField;
use crate::length::Length;
use crate::neighbours::lane_sums::lane_sums;
use crate::neighbours::neighbourhood::Neighbourhood;

/// `[field] kind = "metaball"`: Rosenberg's R_c = 3 and T = 0.2 in units of the particle
/// radius r/2, for which a lone particle's surface lies at one particle radius.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MetaballConfig {
    /// Cut-off radius R_c.
    pub cutoff: Length,
    /// Surface where the summed kernels reach T.
    pub threshold: f32,
    /// α.
    pub exponent: u32,
    /// c.
    pub scale: f32,
}

impl Default for MetaballConfig {
    fn default() -> Self {
        MetaballConfig {
            cutoff: Length::Spacings(1.5),
            threshold: 0.2,
            exponent: 2,
            scale: 0.25,
        }
    }
}

impl MetaballConfig {
    /// Checks the ranges the TOML types cannot express, naming the key.
    pub fn validate(&self) -> Result<()> {
        self.cutoff.check_positive("field.cutoff")?;
        if !(1..=8).contains(&self.exponent) {
            bail_config!(
                "field.exponent must be a whole number from 1 to 8, got {}",
                self.exponent
            );
        }
        if !(self.scale > 0.0 && self.scale.is_finite()) {
            bail_config!("field.scale must be positive, got {}", self.scale);
        }
        if !(self.threshold > 0.0 && self.threshold < self.scale) {
            bail_config!(
                "field.threshold must lie between 0 and field.scale ({}), the kernel's peak, got {}",
                self.scale,
                self.threshold
            );
        }
        Ok(())
    }

    pub(crate) fn resolve(&self, r: f32) -> Metaball {
        Metaball {
            cutoff: self.cutoff.resolve(r),
            threshold: self.threshold,
            exponent: self.exponent as i32,
            scale: self.scale,
        }
    }
}

pub struct Metaball {
    pub cutoff: f32,
    pub threshold: f32,
    pub exponent: i32,
    pub scale: f32,
}

lane_sums! {
    fn kernel_sum(p: (f32, i32)) -> [1] |dx, dy, dz| {
        let (inv_r2, exponent) = p;
        let t = (1.0 - (dx * dx + dy * dy + dz * dz) * inv_r2).max(0.0);
        [t.powi(exponent)]
    }
}

lane_sums! {
    /// Σ α t^(α−1) d_j over the particles inside the cut-off.
    fn kernel_slope_sum(p: (f32, i32)) -> [3] |dx, dy, dz| {
        let (inv_r2, exponent) = p;
        let t = 1.0 - (dx * dx + dy * dy + dz * dz) * inv_r2;
        let inside = f32::from(u8::from(t > 0.0));
        let slope = inside * exponent as f32 * t.max(0.0).powi(exponent - 1);
        [slope * dx, slope * dy, slope * dz]
    }
}

impl ScalarField for Metaball {
    fn support(&self) -> f32 {
        self.cutoff
    }

    fn radial_kernel(&self) -> RadialKernel {
        RadialKernel::Metaball {
            cutoff: self.cutoff,
            exponent: self.exponent,
        }
    }

    fn value(&self, near: &Neighbourhood, x: Vec3) -> f32 {
        let [sum] = kernel_sum(near, x, (1.0 / (self.cutoff * self.cutoff), self.exponent));
        self.threshold - self.scale * sum
    }

    /// −c Σ ∇t^α, with ∇_x t = 2(x_j − x)/R_c².
    fn gradient(&self, near: &Neighbourhood, x: Vec3) -> Vec3 {
        let inv_r2 = 1.0 / (self.cutoff * self.cutoff);
        let s = kernel_slope_sum(near, x, (inv_r2, self.exponent));
        Vec3::from_array(s) * (-2.0 * self.scale * inv_r2)
    }
}
