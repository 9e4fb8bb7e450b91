//! The SPH density (colour) field of Müller et al. 2003 with the cubic spline kernel, the
//! field splashsurf reconstructs: the surface is where the density falls to a fraction `iso`
//! of the rest density. Every particle carries its rest volume r³.

use std::f32::consts::PI;

use anyhow::{Result, bail};
use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::ScalarField;
use crate::config::Length;
use crate::recon::neighbourhood::Neighbourhood;

/// `[field] kind = "density"`: splashsurf's usual settings (smoothing length of two particle
/// radii, i.e. compact support 2r, and iso 0.6).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DensityConfig {
    /// Compact support radius of the cubic spline kernel.
    pub support: Length,
    /// Surface at this fraction of the rest density.
    pub iso: f32,
}

impl Default for DensityConfig {
    fn default() -> Self {
        DensityConfig {
            support: Length::Spacings(2.0),
            iso: 0.6,
        }
    }
}

impl DensityConfig {
    pub fn validate(&self) -> Result<()> {
        self.support.check_positive("field.support")?;
        if !(self.iso > 0.0 && self.iso < 1.0) {
            bail!(
                "field.iso must lie strictly between 0 and 1, got {}",
                self.iso
            );
        }
        Ok(())
    }

    pub fn resolve(&self, r: f32) -> Density {
        Density {
            support: self.support.resolve(r),
            volume: r.powi(3),
            iso: self.iso,
        }
    }
}

pub struct Density {
    pub support: f32,
    /// Rest volume of a particle, m/ρ₀.
    pub volume: f32,
    pub iso: f32,
}

crate::lane_sums! {
    fn spline_sum(inv_h: f32) -> [1] |dx, dy, dz| {
        // Cubic spline with q = d/h over its compact support h, without the factor 8/(π h³).
        let q = (dx * dx + dy * dy + dz * dz).sqrt() * inv_h;
        let a = (1.0 - q).max(0.0);
        let inner = 6.0 * q * q * (q - 1.0) + 1.0;
        [if q <= 0.5 { inner } else { 2.0 * a * a * a }]
    }
}

impl ScalarField for Density {
    fn support(&self) -> f32 {
        self.support
    }

    fn value(&self, near: &Neighbourhood, x: Vec3) -> f32 {
        let [w] = spline_sum(near, x, 1.0 / self.support);
        let sigma = 8.0 / (PI * self.support.powi(3));
        self.iso - self.volume * sigma * w
    }
}
