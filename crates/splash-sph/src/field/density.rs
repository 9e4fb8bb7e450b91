//! The SPH colour field of Müller et al. 2003 with the cubic spline kernel, the field
//! splashsurf reconstructs: c(x) = Σ_j (m_j/ρ_j) W(x − x_j), with each particle's density ρ_j
//! from SPH summation first; the surface is where c falls to `iso`. Inside the fluid c ≈ 1;
//! near the surface the particles' smaller densities give them larger volumes.

use std::f32::consts::PI;

use crate::error::Result;
use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::cubic_spline::{cubic_spline, cubic_spline_slope_over_q};
use super::radial_kernel::RadialKernel;
use super::scalar_field::ScalarField;
use crate::length::Length;
use crate::neighbours::handler_array::HandlerArray;
use crate::neighbours::lane::Lane;
use crate::neighbours::lane_sums::lane_sums;
use crate::neighbours::neighbourhood::{Neighbourhood, map_particles};

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
    /// Checks the ranges the TOML types cannot express, naming the key.
    pub fn validate(&self) -> Result<()> {
        self.support.check_positive("field.support")?;
        if !(self.iso > 0.0 && self.iso < 1.0) {
            bail_config!(
                "field.iso must lie strictly between 0 and 1, got {}",
                self.iso
            );
        }
        Ok(())
    }

    pub(crate) fn resolve(&self, r: f32) -> Density {
        Density {
            support: self.support.resolve(r),
            iso: self.iso,
        }
    }
}

pub struct Density {
    pub support: f32,
    pub iso: f32,
}

/// [`cubic_spline`] of the offset (dx, dy, dz) over the support h (`inv_h` = 1/h).
#[inline(always)]
pub(crate) fn spline<L: Lane>(dx: L, dy: L, dz: L, inv_h: f32) -> L {
    cubic_spline((dx * dx + dy * dy + dz * dz).sqrt() * L::splat(inv_h))
}

/// Σ V_j W'(q_j)/q_j d_j, with q_j = |d_j|/h.
#[inline(always)]
fn weighted_slope<L: Lane>(dx: L, dy: L, dz: L, volume: L, inv_h: f32) -> [L; 3] {
    let q = (dx * dx + dy * dy + dz * dz).sqrt() * L::splat(inv_h);
    let s = volume * cubic_spline_slope_over_q(q);
    [s * dx, s * dy, s * dz]
}

fn sigma(h: f32) -> f32 {
    8.0 / (PI * h.powi(3))
}

lane_sums! {
    vector fn spline_sum(inv_h: f32) -> [1] |dx, dy, dz| {
        [spline(dx, dy, dz, inv_h)]
    }
}

lane_sums! {
    vector fn weighted_spline_sum(inv_h: f32) -> [1] |dx, dy, dz, volume| {
        [volume * spline(dx, dy, dz, inv_h)]
    }
}

lane_sums! {
    vector fn weighted_spline_slope_sum(inv_h: f32) -> [3] |dx, dy, dz, volume| {
        weighted_slope(dx, dy, dz, volume, inv_h)
    }
}

/// Each particle's volume m/ρ = 1/Σ_j W(x_i − x_j) (m = ρ₀·r³ cancels against ρ_i =
/// Σ_j m W_ij), in handler order.
pub fn particle_volumes(handlers: &HandlerArray, support: f32) -> Vec<f32> {
    let inv_h = 1.0 / support;
    map_particles(handlers, support, |near, x| {
        let [w] = spline_sum(near, x, inv_h);
        particle_volume(w, support)
    })
}

/// A particle's volume from Σ_j W(x_i − x_j) / σ, the sum of its [`spline`]s over the support.
#[inline]
pub(crate) fn particle_volume(splines: f32, support: f32) -> f32 {
    1.0 / (sigma(support) * splines)
}

impl ScalarField for Density {
    fn support(&self) -> f32 {
        self.support
    }

    fn radial_kernel(&self) -> RadialKernel {
        RadialKernel::CubicSpline {
            support: self.support,
        }
    }

    fn particle_channels(&self, handlers: &HandlerArray) -> Vec<Vec<f32>> {
        vec![particle_volumes(handlers, self.support)]
    }

    fn volume_support(&self) -> Option<f32> {
        Some(self.support)
    }

    fn value(&self, near: &Neighbourhood, x: Vec3) -> f32 {
        let [w] = weighted_spline_sum(near, x, 1.0 / self.support);
        self.iso - sigma(self.support) * w
    }

    /// −σ Σ V_j ∇W: with q = |x_j − x|/h, ∇_x q = −(x_j − x)/(q h²).
    fn gradient(&self, near: &Neighbourhood, x: Vec3) -> Vec3 {
        let inv_h = 1.0 / self.support;
        let s = weighted_spline_slope_sum(near, x, inv_h);
        Vec3::from_array(s) * (sigma(self.support) * inv_h * inv_h)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn branch_free_spline_is_the_piecewise_cubic() {
        for i in 0..=120 {
            let q = i as f32 / 100.0;
            let expected = if q <= 0.5 {
                6.0 * q * q * q - 6.0 * q * q + 1.0
            } else if q <= 1.0 {
                2.0 * (1.0 - q).powi(3)
            } else {
                0.0
            };
            assert!((spline(q, 0.0, 0.0, 1.0) - expected).abs() < 1e-6, "q {q}");
        }
    }

    #[test]
    fn lane_sums_are_the_same_on_every_path() {
        use crate::neighbours::lane_sums::tests::on_every_path;
        let mut next = crate::tests::common::uniform(5);
        // Particles around the origin, one at each query point and one on the support's
        // edge (q = 0 and q = 1), with volumes of a few magnitudes.
        let xs = [
            Vec3::ZERO,
            Vec3::new(0.3, -0.2, 0.1),
            Vec3::new(0.9, 0.9, -0.4),
        ];
        let mut points: Vec<Vec3> = (0..205)
            .map(|_| crate::tests::common::uniform_point(&mut next) * 3.0 - 1.5)
            .collect();
        points.extend(xs);
        points.push(xs[1] + Vec3::new(0.0, 1.0, 0.0));
        let volumes: Vec<f32> = points.iter().map(|_| (next() * 6.0 - 3.0).exp()).collect();
        let mut near = Neighbourhood::default();
        let all = (0..points.len()).map(|i| (i, true));
        near.pick(Vec3::ZERO, all, &points, &[volumes]);
        for x in xs {
            let sums = on_every_path(|| {
                (
                    spline_sum(&near, x, 1.0).map(f32::to_bits),
                    weighted_spline_sum(&near, x, 1.0).map(f32::to_bits),
                    weighted_spline_slope_sum(&near, x, 1.0).map(f32::to_bits),
                )
            });
            for (path, s) in &sums {
                assert_eq!(s, &sums[0].1, "{path:?} at {x}");
            }
            let w = f32::from_bits(sums[0].1.1[0]);
            assert!(w > 0.0 && w.is_finite(), "{w}");
        }
    }

    #[test]
    fn the_kernel_integrates_to_one() {
        // Σ over a fine lattice of W·volume ≈ 1.
        let (h, step) = (1.0f32, 0.05f32);
        let n = (h / step) as i32 + 1;
        let mut sum = 0.0;
        for z in -n..=n {
            for y in -n..=n {
                for x in -n..=n {
                    let d = glam::Vec3::new(x as f32, y as f32, z as f32) * step;
                    sum += spline(d.x, d.y, d.z, 1.0 / h) * sigma(h) * step.powi(3);
                }
            }
        }
        assert!((sum - 1.0).abs() < 1e-3, "{sum}");
    }
}
