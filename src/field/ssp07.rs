//! The improved signed distance of Solenthaler et al. 2007, as used by Akinci et al. 2012
//! (Sec. 3, eqs. 1–5).

use anyhow::{Result, bail};
use glam::{DMat3, DVec3, Vec3};
use serde::{Deserialize, Serialize};

use super::ScalarField;
use crate::config::Length;
use crate::recon::neighbourhood::Neighbourhood;

/// `[field] kind = "ssp07"`: the paper's defaults.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Ssp07Config {
    /// Influence radius R of eq. 4 (Sec. 3: below 4r surfaces get bumpy).
    pub support: Length,
    /// r̄ of eq. 1 (the paper uses r).
    pub radius: Length,
    /// Eigenvalue thresholds of eqs. 2–3 (SSP07 proposed t_high = 2; Akinci et al. use 3.5).
    pub t_low: f32,
    pub t_high: f32,
}

impl Default for Ssp07Config {
    fn default() -> Self {
        Ssp07Config {
            support: Length::Spacings(4.0),
            radius: Length::Spacings(1.0),
            t_low: 0.4,
            t_high: 3.5,
        }
    }
}

impl Ssp07Config {
    pub fn validate(&self) -> Result<()> {
        self.support.check_positive("field.support")?;
        self.radius.check_positive("field.radius")?;
        if !(self.t_low.is_finite() && self.t_high.is_finite() && self.t_low < self.t_high) {
            bail!(
                "field.t_low ({}) must be below field.t_high ({})",
                self.t_low,
                self.t_high
            );
        }
        Ok(())
    }

    pub fn resolve(&self, r: f32) -> Ssp07 {
        Ssp07 {
            support: self.support.resolve(r),
            radius: self.radius.resolve(r),
            t_low: self.t_low,
            t_high: self.t_high,
        }
    }
}

pub struct Ssp07 {
    /// Influence radius R (eq. 4).
    pub support: f32,
    /// r̄ (eq. 1).
    pub radius: f32,
    pub t_low: f32,
    pub t_high: f32,
}

impl ScalarField for Ssp07 {
    fn support(&self) -> f32 {
        self.support
    }

    fn value(&self, near: &Neighbourhood, x: Vec3) -> f32 {
        self.value_of_sums(&Sums::over(near, x, 1.0 / (self.support * self.support)))
    }
}

impl Ssp07 {
    /// eq. 1 from the kernel sums at a point, however they were accumulated (the gather above,
    /// or the scatter engine adding one particle at a time with [`Sums::add`]).
    pub fn value_of_sums(&self, s: &Sums) -> f32 {
        if s.k <= 0.0 {
            // No particle in reach: the limit of eq. 1 as the last particle leaves the support
            // (x̄ at distance R, ∇x̄ = 0, f = 1).
            return self.support - self.radius;
        }
        let k = f64::from(s.k);
        // x̄ − x, with particle offsets d_j = x_j − x.
        let m = DVec3::new(s.kd[0].into(), s.kd[1].into(), s.kd[2].into()) / k;
        let f = self.f(largest_eigenvalue_real_part(&s.jacobian(m, self.support)));
        (m.length() - f64::from(self.radius) * f) as f32
    }

    /// eqs. 2–3. γ is clamped to [0, 1] so that f falls smoothly from 1 to 0 between t_low and
    /// t_high and stays 0 beyond: the paper leaves EV_max > t_high unstated, where the cubic
    /// would turn negative.
    fn f(&self, ev_max: f64) -> f64 {
        let (lo, hi) = (f64::from(self.t_low), f64::from(self.t_high));
        if ev_max < lo {
            return 1.0;
        }
        let g = ((hi - ev_max) / (hi - lo)).clamp(0.0, 1.0);
        g * g * g - 3.0 * g * g + 3.0 * g
    }
}

/// Kernel sums over the neighbours, with s_j = |d_j|/R, t_j = 1 − s_j² clamped at 0,
/// k_j = t_j³ (eq. 5) and w_j = t_j².
#[derive(Debug, Clone, Copy, Default)]
pub struct Sums {
    k: f32,
    kd: [f32; 3],
    wd: [f32; 3],
    /// Σ w d dᵀ: xx, yy, zz, xy, xz, yz.
    wdd: [f32; 6],
}

crate::lane_sums! {
    fn ssp07_sums(inv_r2: f32) -> [13] |dx, dy, dz| {
        let t = (1.0 - (dx * dx + dy * dy + dz * dz) * inv_r2).max(0.0);
        let w = t * t;
        let k = w * t;
        let (wx, wy, wz) = (w * dx, w * dy, w * dz);
        [k, k * dx, k * dy, k * dz, wx, wy, wz, wx * dx, wy * dy, wz * dz, wx * dy, wx * dz, wy * dz]
    }
}

impl Sums {
    /// Adds the particle at offset `d = x_j − x` from the point: one step of a scatter.
    #[inline(always)]
    pub fn add(&mut self, d: Vec3, inv_r2: f32) {
        let t = (1.0 - d.length_squared() * inv_r2).max(0.0);
        let w = t * t;
        let k = w * t;
        let (wx, wy, wz) = (w * d.x, w * d.y, w * d.z);
        self.k += k;
        self.kd[0] += k * d.x;
        self.kd[1] += k * d.y;
        self.kd[2] += k * d.z;
        self.wd[0] += wx;
        self.wd[1] += wy;
        self.wd[2] += wz;
        self.wdd[0] += wx * d.x;
        self.wdd[1] += wy * d.y;
        self.wdd[2] += wz * d.z;
        self.wdd[3] += wx * d.y;
        self.wdd[4] += wx * d.z;
        self.wdd[5] += wy * d.z;
    }

    fn over(near: &Neighbourhood, x: Vec3, inv_r2: f32) -> Sums {
        let s = ssp07_sums(near, x, inv_r2);
        Sums {
            k: s[0],
            kd: [s[1], s[2], s[3]],
            wd: [s[4], s[5], s[6]],
            wdd: [s[7], s[8], s[9], s[10], s[11], s[12]],
        }
    }

    /// ∇x̄ of eq. 4, analytically. With d_j = x_j − x and k_j = (1 − |d_j|²/R²)³,
    /// ∇k_j = 6 w_j d_j / R², so
    ///   ∂x̄_a/∂x_b = Σ_j (x_j − x̄)_a ∂_b k_j / Σ_j k_j
    ///             = 6/(R² Σk) · (Σ_j w_j d_j d_jᵀ − m (Σ_j w_j d_j)ᵀ)_ab,  m = x̄ − x.
    fn jacobian(&self, m: DVec3, support: f32) -> DMat3 {
        let c = 6.0 / (f64::from(support).powi(2) * f64::from(self.k));
        let [xx, yy, zz, xy, xz, yz] = self.wdd.map(f64::from);
        let covariance = DMat3::from_cols(
            DVec3::new(xx, xy, xz),
            DVec3::new(xy, yy, yz),
            DVec3::new(xz, yz, zz),
        );
        let wd = DVec3::new(self.wd[0].into(), self.wd[1].into(), self.wd[2].into());
        // Column b of m wdᵀ is m · wd_b.
        let outer = DMat3::from_cols(m * wd.x, m * wd.y, m * wd.z);
        (covariance - outer) * c
    }
}

/// Largest real part among the eigenvalues of a 3×3 matrix, from its characteristic cubic.
/// ∇x̄ is not symmetric, so a complex pair may occur; its real part then competes too.
fn largest_eigenvalue_real_part(a: &DMat3) -> f64 {
    let trace = a.x_axis.x + a.y_axis.y + a.z_axis.z;
    let minors = a.x_axis.x * a.y_axis.y - a.y_axis.x * a.x_axis.y + a.x_axis.x * a.z_axis.z
        - a.z_axis.x * a.x_axis.z
        + a.y_axis.y * a.z_axis.z
        - a.z_axis.y * a.y_axis.z;
    let det = a.determinant();
    // λ³ − trace λ² + minors λ − det = 0; with λ = μ + trace/3: μ³ + pμ + q = 0.
    let shift = trace / 3.0;
    let p = minors - trace * trace / 3.0;
    let q = -2.0 * trace.powi(3) / 27.0 + trace * minors / 3.0 - det;
    let discriminant = (q / 2.0).powi(2) + (p / 3.0).powi(3);
    let mu = if discriminant > 0.0 {
        let s = discriminant.sqrt();
        let real = (-q / 2.0 + s).cbrt() + (-q / 2.0 - s).cbrt();
        // The complex pair has real part −real/2.
        real.max(-real / 2.0)
    } else if p < 0.0 {
        let r = (-p / 3.0).sqrt();
        let cos = (-q / (2.0 * r.powi(3))).clamp(-1.0, 1.0);
        2.0 * r * (cos.acos() / 3.0).cos()
    } else {
        0.0
    };
    mu + shift
}

#[cfg(test)]
mod tests {
    use super::*;

    fn near(points: &[Vec3]) -> Neighbourhood {
        let mut n = Neighbourhood::default();
        n.set(Vec3::ZERO, points);
        n
    }

    fn field() -> Ssp07 {
        Ssp07 {
            support: 4.0,
            radius: 1.0,
            t_low: 0.4,
            t_high: 3.5,
        }
    }

    #[test]
    fn eigenvalues_of_known_matrices() {
        let diag = DMat3::from_diagonal(DVec3::new(0.5, 3.0, -1.0));
        assert!((largest_eigenvalue_real_part(&diag) - 3.0).abs() < 1e-9);
        // Rotation by 90° about z scaled by 2, plus 0.5 on z: eigenvalues ±2i and 0.5.
        let rot = DMat3::from_cols(
            DVec3::new(0.0, 2.0, 0.0),
            DVec3::new(-2.0, 0.0, 0.0),
            DVec3::new(0.0, 0.0, 0.5),
        );
        assert!((largest_eigenvalue_real_part(&rot) - 0.5).abs() < 1e-9);
        let triple = DMat3::from_diagonal(DVec3::splat(1.5));
        assert!((largest_eigenvalue_real_part(&triple) - 1.5).abs() < 1e-6);
    }

    #[test]
    fn lone_particle_is_a_ball_of_radius_r_bar() {
        let f = field();
        let n = near(&[Vec3::ZERO]);
        for d in [0.0f32, 0.5, 0.99, 1.01, 2.0, 3.9] {
            let v = f.value(&n, Vec3::new(d, 0.0, 0.0));
            assert!((v - (d - 1.0)).abs() < 1e-5, "d {d}: {v}");
        }
        assert_eq!(f.value(&n, Vec3::new(5.0, 0.0, 0.0)), 3.0);
    }

    #[test]
    fn scattered_sums_give_the_gathered_value() {
        let f = field();
        let pts: Vec<Vec3> = (0..60)
            .map(|i| {
                let a = i as f32 * 2.399;
                Vec3::new(a.cos() * 2.3, a.sin() * 2.1, (i as f32 * 0.37).sin() * 2.5)
            })
            .collect();
        let n = near(&pts);
        for x in [
            Vec3::ZERO,
            Vec3::new(1.5, -0.5, 2.0),
            Vec3::new(3.0, 3.0, 0.0),
        ] {
            let mut s = Sums::default();
            for &p in &pts {
                s.add(p - x, 1.0 / 16.0);
            }
            let (a, b) = (f.value_of_sums(&s), f.value(&n, x));
            assert!((a - b).abs() < 1e-5, "at {x}: scatter {a}, gather {b}");
        }
    }

    #[test]
    fn jacobian_matches_finite_differences_of_the_mean() {
        let pts: Vec<Vec3> = (0..40)
            .map(|i| {
                let a = i as f32 * 2.399;
                Vec3::new(a.cos() * 1.3, a.sin() * 1.1, (i as f32 * 0.37).sin() * 1.5)
            })
            .collect();
        let n = near(&pts);
        let mean = |x: Vec3| {
            let s = Sums::over(&n, x, 1.0 / 16.0);
            DVec3::new(s.kd[0].into(), s.kd[1].into(), s.kd[2].into()) / f64::from(s.k)
                + x.as_dvec3()
        };
        let x = Vec3::new(0.3, -0.2, 0.4);
        let s = Sums::over(&n, x, 1.0 / 16.0);
        let j = s.jacobian(mean(x) - x.as_dvec3(), 4.0);
        let h = 1e-2f32;
        for b in 0..3 {
            let e = Vec3::AXES[b] * h;
            let fd = (mean(x + e) - mean(x - e)) / (2.0 * f64::from(h));
            for a in 0..3 {
                assert!(
                    (j.col(b)[a] - fd[a]).abs() < 2e-3,
                    "({a},{b}): {} vs {}",
                    j.col(b)[a],
                    fd[a]
                );
            }
        }
    }
}
