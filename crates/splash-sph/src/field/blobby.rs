//! Blinn's blobby molecules (1982): Gaussian bumps exp(B(1 − d²/R²)), which equal 1 at the
//! atom radius R, summed and compared with a threshold. Each bump is lowered by its value at
//! the cut-off, where it has fallen to `epsilon`, so that it reaches 0 there continuously.

use crate::error::Result;
use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::radial_kernel::RadialKernel;
use super::scalar_field::ScalarField;
use crate::length::Length;
use crate::neighbours::lane_sums::lane_sums;
use crate::neighbours::neighbourhood::Neighbourhood;

/// `[field] kind = "blobby"`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BlobbyConfig {
    /// Atom radius R: a lone particle's surface at threshold 1.
    pub radius: Length,
    /// Blinn's blobbiness B: larger is tighter, smaller is blobbier.
    pub blobbiness: f32,
    /// Surface where the summed bumps reach this.
    pub threshold: f32,
    /// A bump is cut off where it falls to this (relative to its value 1 at R).
    pub epsilon: f32,
}

impl Default for BlobbyConfig {
    fn default() -> Self {
        BlobbyConfig {
            radius: Length::Spacings(0.75),
            blobbiness: 2.0,
            threshold: 1.0,
            epsilon: 1e-3,
        }
    }
}

impl BlobbyConfig {
    /// Checks the ranges the TOML types cannot express, naming the key.
    pub fn validate(&self) -> Result<()> {
        self.radius.check_positive("field.radius")?;
        if !(self.blobbiness > 0.0 && self.blobbiness.is_finite()) {
            bail_config!("field.blobbiness must be positive, got {}", self.blobbiness);
        }
        if !(self.threshold > 0.0 && self.threshold.is_finite()) {
            bail_config!("field.threshold must be positive, got {}", self.threshold);
        }
        if !(self.epsilon > 0.0 && self.epsilon < 1.0) {
            bail_config!(
                "field.epsilon must lie strictly between 0 and 1, got {}",
                self.epsilon
            );
        }
        Ok(())
    }

    pub(crate) fn resolve(&self, r: f32) -> Blobby {
        let radius = self.radius.resolve(r);
        // exp(B(1 − s²)) = ε at s² = 1 + ln(1/ε)/B.
        let cutoff_s2 = 1.0 + (1.0 / self.epsilon).ln() / self.blobbiness;
        Blobby {
            radius,
            blobbiness: self.blobbiness,
            threshold: self.threshold,
            cutoff_s2,
        }
    }
}

pub struct Blobby {
    pub radius: f32,
    pub blobbiness: f32,
    pub threshold: f32,
    /// (cut-off distance / R)².
    pub cutoff_s2: f32,
}

#[derive(Clone, Copy)]
struct Shape {
    inv_r2: f32,
    b: f32,
    cutoff_s2: f32,
}

lane_sums! {
    fn bump_sum(p: Shape) -> [1] |dx, dy, dz| {
        let s2 = (dx * dx + dy * dy + dz * dz) * p.inv_r2;
        let bump = (p.b * (1.0 - s2.min(p.cutoff_s2))).exp() - (p.b * (1.0 - p.cutoff_s2)).exp();
        [bump]
    }
}

lane_sums! {
    /// Σ ∂bump/∂s² · d_j over the particles inside the cut-off.
    fn bump_slope_sum(p: Shape) -> [3] |dx, dy, dz| {
        let s2 = (dx * dx + dy * dy + dz * dz) * p.inv_r2;
        let inside = f32::from(u8::from(s2 < p.cutoff_s2));
        let slope = inside * (p.b * (1.0 - s2.min(p.cutoff_s2))).exp();
        [slope * dx, slope * dy, slope * dz]
    }
}

impl ScalarField for Blobby {
    fn support(&self) -> f32 {
        self.radius * self.cutoff_s2.sqrt()
    }

    fn radial_kernel(&self) -> RadialKernel {
        RadialKernel::Blobby {
            radius: self.radius,
            blobbiness: self.blobbiness,
            cutoff_s2: self.cutoff_s2,
        }
    }

    fn value(&self, near: &Neighbourhood, x: Vec3) -> f32 {
        let [sum] = bump_sum(near, x, self.shape());
        self.threshold - sum
    }

    /// −Σ ∇ exp(B(1 − s²)), with ∇_x s² = −2(x_j − x)/R².
    fn gradient(&self, near: &Neighbourhood, x: Vec3) -> Vec3 {
        let shape = self.shape();
        let s = bump_slope_sum(near, x, shape);
        Vec3::from_array(s) * (-2.0 * shape.b * shape.inv_r2)
    }
}

impl Blobby {
    fn shape(&self) -> Shape {
        Shape {
            inv_r2: 1.0 / (self.radius * self.radius),
            b: self.blobbiness,
            cutoff_s2: self.cutoff_s2,
        }
    }
}
