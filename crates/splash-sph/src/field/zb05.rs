//! The signed distance of Zhu & Bridson 2005: φ(x) = |x − x̄| − r̄, with x̄ the kernel-weighted
//! mean of eq. 4 of Akinci et al. 2012 (SSP07 without its eigenvalue correction f).

use crate::error::Result;
use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::radial_kernel::RadialKernel;
use super::scalar_field::ScalarField;
use super::ssp07::{MeanDistance, Sums};
use crate::length::Length;
use crate::neighbours::lane_sums::lane_sums;
use crate::neighbours::neighbourhood::Neighbourhood;

/// `[field] kind = "zb05"`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Zb05Config {
    /// Influence radius R (Zhu & Bridson: below 4r surfaces get bumpy).
    pub support: Length,
    /// r̄, the radius of a lone particle's ball.
    pub radius: Length,
}

impl Default for Zb05Config {
    fn default() -> Self {
        Zb05Config {
            support: Length::Spacings(4.0),
            radius: Length::Spacings(1.0),
        }
    }
}

impl Zb05Config {
    /// Checks the ranges the TOML types cannot express, naming the key.
    pub fn validate(&self) -> Result<()> {
        self.support.check_positive("field.support")?;
        self.radius.check_positive("field.radius")
    }

    pub(crate) fn resolve(&self, r: f32) -> Zb05 {
        Zb05 {
            support: self.support.resolve(r),
            radius: self.radius.resolve(r),
        }
    }
}

pub struct Zb05 {
    pub support: f32,
    pub radius: f32,
}

lane_sums! {
    fn mean_sums(inv_r2: f32) -> [4] |dx, dy, dz| {
        let t = (1.0 - (dx * dx + dy * dy + dz * dz) * inv_r2).max(0.0);
        let k = t * t * t;
        [k, k * dx, k * dy, k * dz]
    }
}

impl ScalarField for Zb05 {
    fn support(&self) -> f32 {
        self.support
    }

    fn is_distance(&self) -> bool {
        true
    }

    fn radial_kernel(&self) -> RadialKernel {
        RadialKernel::Poly6 {
            support: self.support,
        }
    }

    fn value(&self, near: &Neighbourhood, x: Vec3) -> f32 {
        let [k, kx, ky, kz] = mean_sums(near, x, 1.0 / (self.support * self.support));
        if k <= 0.0 {
            // The limit as the last particle leaves the support.
            return self.support - self.radius;
        }
        Vec3::new(kx, ky, kz).length() / k - self.radius
    }

    /// ∇|x̄ − x|, as in SSP07's first term.
    fn gradient(&self, near: &Neighbourhood, x: Vec3) -> Vec3 {
        let sums = Sums::over(near, x, 1.0 / (self.support * self.support));
        MeanDistance::of(&sums, self.support).map_or(Vec3::ZERO, |m| m.gradient.as_vec3())
    }
}
