//! The improved signed distance of Solenthaler et al. 2007, as used by Akinci et al. 2012
//! (Sec. 3, eqs. 1–5).

use crate::error::Result;
use glam::{DMat3, DVec3, Vec3};
use serde::{Deserialize, Serialize};

use super::radial_kernel::RadialKernel;
use super::scalar_field::{Sampled, ScalarField, Scattering, SignFirst};
use crate::length::Length;
use crate::neighbours::lane_sums::lane_sums;
use crate::neighbours::neighbourhood::Neighbourhood;

/// `[field] kind = "ssp07"`: the paper's defaults.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Ssp07Config {
    /// Influence radius R of eq. 4 (Sec. 3: below 4r surfaces get bumpy).
    pub support: Length,
    /// r̄ of eq. 1 (the paper uses r).
    pub radius: Length,
    /// Eigenvalue thresholds of eqs. 2–3 (SSP07 proposed t_high = 2; Akinci et al. use 3.5):
    /// below `t_low` the surface sits r̄ from the particles' mean…
    pub t_low: f32,
    /// …and above `t_high` on it.
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
    /// Checks the ranges the TOML types cannot express, naming the key.
    pub fn validate(&self) -> Result<()> {
        self.support.check_positive("field.support")?;
        self.radius.check_positive("field.radius")?;
        if !(self.t_low.is_finite() && self.t_high.is_finite() && self.t_low < self.t_high) {
            bail_config!(
                "field.t_low ({}) must be below field.t_high ({})",
                self.t_low,
                self.t_high
            );
        }
        Ok(())
    }

    pub(crate) fn resolve(&self, r: f32) -> Ssp07 {
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

    fn is_distance(&self) -> bool {
        true
    }

    fn radial_kernel(&self) -> RadialKernel {
        RadialKernel::Poly6 {
            support: self.support,
        }
    }

    fn scattering(&self) -> Option<&dyn Scattering> {
        Some(self)
    }

    fn sign_first(&self) -> Option<&dyn SignFirst> {
        Some(self)
    }

    fn value(&self, near: &Neighbourhood, x: Vec3) -> f32 {
        self.value_of(&Sums::over(near, x, 1.0 / (self.support * self.support)))
    }

    /// ∇φ = (∇x̄ − I)ᵀ m̂ − r̄ f'(λ) ∇λ from eq. 1, with m = x̄ − x and λ = EV_max; ∇λ follows
    /// from the derivatives of ∇x̄ (see [`GradientSums`]).
    fn gradient(&self, near: &Neighbourhood, x: Vec3) -> Vec3 {
        let g = GradientSums::over(near, x, 1.0 / (self.support * self.support));
        let Some(mean) = MeanDistance::of(&g.sums, self.support) else {
            return Vec3::ZERO;
        };
        let ev = largest_eigenvalue(&mean.jacobian);
        let slope = self.f_slope(ev.re);
        let mut grad = mean.gradient;
        if slope != 0.0 {
            grad -= f64::from(self.radius) * slope * g.eigenvalue_gradient(&mean, ev, self.support);
        }
        grad.as_vec3()
    }
}

impl Scattering for Ssp07 {
    fn sums_per_vertex(&self) -> usize {
        size_of::<Sums>() / size_of::<f32>()
    }

    fn add_to_row(&self, sums: &mut [f32], p: Vec3, xs: &[f32], y: f32, z: f32) {
        let inv_r2 = 1.0 / (self.support * self.support);
        let sums: &mut [Sums] = bytemuck::cast_slice_mut(sums);
        let (dy, dz) = (p.y - y, p.z - z);
        for (s, &x) in sums.iter_mut().zip(xs) {
            s.add(Vec3::new(p.x - x, dy, dz), inv_r2);
        }
    }

    fn value_of_sums(&self, sums: &[f32]) -> f32 {
        self.value_of(bytemuck::from_bytes(bytemuck::cast_slice(sums)))
    }
}

/// The sign of eq. 1 before its eigenvalue: f falls with EV_max (eqs. 2–3) and lies in
/// [0, 1], and the largest real part of ∇x̄'s eigenvalues lies between their mean (tr/3) and
/// the largest eigenvalue of its symmetric part (Bendixson), which Gershgorin's discs bound.
/// So φ ≥ |m| − r̄ and φ ≥ |m| − r̄ f(tr/3), and φ ≤ |m| − r̄ f(that bound): far from the
/// surface one of them settles the sign, and the eigenvalue (a third of the sampling's time
/// at cell r/2) is needed only near it.
impl SignFirst for Ssp07 {
    fn value_or_sign(&self, near: &Neighbourhood, x: Vec3, margin: f32) -> Sampled {
        let s = Sums::over(near, x, 1.0 / (self.support * self.support));
        let Some(m) = s.mean_offset() else {
            return Sampled::Value(self.value_of(&s));
        };
        let (d, r) = (m.length(), f64::from(self.radius));
        // The bounds' rounding, and the cubic's near a triple eigenvalue, stay far below this.
        let margin = f64::from(margin).max(1e-4 * r);
        if d - r > margin {
            return Sampled::Beyond { inside: false };
        }
        let jacobian = s.jacobian(m, self.support);
        let j = jacobian.to_cols_array_2d();
        let trace = j[0][0] + j[1][1] + j[2][2];
        if d - r * self.f(trace / 3.0) > margin {
            return Sampled::Beyond { inside: false };
        }
        let disc = |a: usize| {
            let (b, c) = ((a + 1) % 3, (a + 2) % 3);
            j[a][a] + 0.5 * ((j[a][b] + j[b][a]).abs() + (j[a][c] + j[c][a]).abs())
        };
        let upper = disc(0).max(disc(1)).max(disc(2));
        if d - r * self.f(upper) < -margin {
            return Sampled::Beyond { inside: true };
        }
        Sampled::Value(self.value_at(m, &jacobian))
    }
}

impl Ssp07 {
    /// eq. 1 from the kernel sums at a point, however they were accumulated (the gather above,
    /// or the scatter engine adding one particle at a time with [`Sums::add`]).
    fn value_of(&self, s: &Sums) -> f32 {
        match s.mean_offset() {
            Some(m) => self.value_at(m, &s.jacobian(m, self.support)),
            // No particle in reach: the limit of eq. 1 as the last particle leaves the support
            // (x̄ at distance R, ∇x̄ = 0, f = 1).
            None => self.support - self.radius,
        }
    }

    /// eq. 1 from m = x̄ − x and ∇x̄.
    fn value_at(&self, m: DVec3, jacobian: &DMat3) -> f32 {
        let f = self.f(largest_eigenvalue(jacobian).re);
        (m.length() - f64::from(self.radius) * f) as f32
    }

    /// df/dλ of eqs. 2–3: 3(1 − γ)² dγ/dλ where γ is not clamped, else 0.
    fn f_slope(&self, ev_max: f64) -> f64 {
        let (lo, hi) = (f64::from(self.t_low), f64::from(self.t_high));
        let g = (hi - ev_max) / (hi - lo);
        if ev_max < lo || !(0.0..1.0).contains(&g) {
            return 0.0;
        }
        -3.0 * (1.0 - g).powi(2) / (hi - lo)
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
#[derive(Debug, Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct Sums {
    k: f32,
    kd: [f32; 3],
    wd: [f32; 3],
    /// Σ w d dᵀ: xx, yy, zz, xy, xz, yz.
    wdd: [f32; 6],
}

/// One particle's terms of [`Sums`] at offset d = x_j − x, with its t.
#[inline(always)]
fn sum_terms(dx: f32, dy: f32, dz: f32, inv_r2: f32) -> (f32, [f32; 13]) {
    let t = (1.0 - (dx * dx + dy * dy + dz * dz) * inv_r2).max(0.0);
    let w = t * t;
    let k = w * t;
    let (wx, wy, wz) = (w * dx, w * dy, w * dz);
    let terms = [
        k,
        k * dx,
        k * dy,
        k * dz,
        wx,
        wy,
        wz,
        wx * dx,
        wy * dy,
        wz * dz,
        wx * dy,
        wx * dz,
        wy * dz,
    ];
    (t, terms)
}

lane_sums! {
    fn ssp07_sums(inv_r2: f32) -> [13] |dx, dy, dz| {
        sum_terms(dx, dy, dz, inv_r2).1
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

    pub(super) fn over(near: &Neighbourhood, x: Vec3, inv_r2: f32) -> Sums {
        let s = ssp07_sums(near, x, inv_r2);
        Sums {
            k: s[0],
            kd: [s[1], s[2], s[3]],
            wd: [s[4], s[5], s[6]],
            wdd: [s[7], s[8], s[9], s[10], s[11], s[12]],
        }
    }

    /// m = x̄ − x (eq. 4, with particle offsets d_j = x_j − x); `None` where no particle is in
    /// reach.
    fn mean_offset(&self) -> Option<DVec3> {
        if self.k <= 0.0 {
            return None;
        }
        Some(
            DVec3::new(self.kd[0].into(), self.kd[1].into(), self.kd[2].into()) / f64::from(self.k),
        )
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

/// The distance |x̄ − x| to the kernel-weighted mean (eq. 4), with its gradient.
pub(super) struct MeanDistance {
    /// m = x̄ − x.
    pub m: DVec3,
    /// ∇x̄.
    pub jacobian: DMat3,
    /// ∇|m| = (∇x̄ − I)ᵀ m̂.
    pub gradient: DVec3,
}

impl MeanDistance {
    /// `None` where no particle is in reach (the field is constant there).
    pub fn of(s: &Sums, support: f32) -> Option<MeanDistance> {
        let m = s.mean_offset()?;
        let jacobian = s.jacobian(m, support);
        let gradient = (jacobian - DMat3::IDENTITY).transpose() * m.normalize_or_zero();
        Some(MeanDistance {
            m,
            jacobian,
            gradient,
        })
    }
}

/// [`Sums`] plus the sums that differentiate ∇x̄ once more: with t_j, w_j and d_j as there,
/// W = Σ w, S = Σ t d dᵀ and T = Σ t d⊗d⊗d. Writing J = C X, C = 6/(R² Σk),
/// X = Σ w d dᵀ − m (Σ w d)ᵀ = A − m Bᵀ, and ∂t_j/∂x_c = 2 d_c/R²:
///   ∂J_ab/∂x_c = −C B_c J_ab + C (4/R² T_abc − δ_bc B_a − J_ac B_b − 4/R² m_a S_bc + δ_bc m_a W).
struct GradientSums {
    sums: Sums,
    w: f32,
    /// xx, yy, zz, xy, xz, yz.
    s: [f32; 6],
    /// xxx, yyy, zzz, xxy, xxz, xyy, yyz, xzz, yzz, xyz.
    t: [f32; 10],
}

lane_sums! {
    fn ssp07_gradient_sums(inv_r2: f32) -> [30] |dx, dy, dz| {
        let (t, [k, kx, ky, kz, wx, wy, wz, wxx, wyy, wzz, wxy, wxz, wyz]) =
            sum_terms(dx, dy, dz, inv_r2);
        let w = t * t;
        let (tx, ty, tz) = (t * dx, t * dy, t * dz);
        let (txx, tyy, tzz, txy, txz, tyz) = (tx * dx, ty * dy, tz * dz, tx * dy, tx * dz, ty * dz);
        [
            k, kx, ky, kz, wx, wy, wz, wxx, wyy, wzz, wxy, wxz, wyz,
            w, txx, tyy, tzz, txy, txz, tyz,
            txx * dx, tyy * dy, tzz * dz, txx * dy, txx * dz, txy * dy, tyy * dz, txz * dz, tyz * dz,
            txy * dz,
        ]
    }
}

/// The slot of T_abc in [`GradientSums::t`], for every order of the indices.
const T_INDEX: [[[usize; 3]; 3]; 3] = {
    // Slots by sorted indices: xxx yyy zzz xxy xxz xyy yyz xzz yzz xyz.
    const SORTED: [[usize; 3]; 10] = [
        [0, 0, 0],
        [1, 1, 1],
        [2, 2, 2],
        [0, 0, 1],
        [0, 0, 2],
        [0, 1, 1],
        [1, 1, 2],
        [0, 2, 2],
        [1, 2, 2],
        [0, 1, 2],
    ];
    let mut table = [[[0; 3]; 3]; 3];
    let mut slot = 0;
    while slot < 10 {
        let [a, b, c] = SORTED[slot];
        // Every permutation of (a, b, c).
        let perms = [
            [a, b, c],
            [a, c, b],
            [b, a, c],
            [b, c, a],
            [c, a, b],
            [c, b, a],
        ];
        let mut p = 0;
        while p < 6 {
            let [i, j, k] = perms[p];
            table[i][j][k] = slot;
            p += 1;
        }
        slot += 1;
    }
    table
};

impl GradientSums {
    fn over(near: &Neighbourhood, x: Vec3, inv_r2: f32) -> GradientSums {
        let s = ssp07_gradient_sums(near, x, inv_r2);
        GradientSums {
            sums: Sums {
                k: s[0],
                kd: [s[1], s[2], s[3]],
                wd: [s[4], s[5], s[6]],
                wdd: [s[7], s[8], s[9], s[10], s[11], s[12]],
            },
            w: s[13],
            s: std::array::from_fn(|i| s[14 + i]),
            t: std::array::from_fn(|i| s[20 + i]),
        }
    }

    fn s(&self, a: usize, b: usize) -> f64 {
        const INDEX: [[usize; 3]; 3] = [[0, 3, 4], [3, 1, 5], [4, 5, 2]];
        f64::from(self.s[INDEX[a][b]])
    }

    fn t(&self, a: usize, b: usize, c: usize) -> f64 {
        f64::from(self.t[T_INDEX[a][b][c]])
    }

    /// ∂(∇x̄)/∂x_c, by the formula above.
    fn jacobian_derivative(&self, mean: &MeanDistance, support: f32, c: usize) -> DMat3 {
        let r2 = f64::from(support).powi(2);
        let cc = 6.0 / (r2 * f64::from(self.sums.k));
        let b = DVec3::from_array(self.sums.wd.map(f64::from));
        let (j, m, w) = (&mean.jacobian, mean.m, f64::from(self.w));
        DMat3::from_cols_array_2d(&std::array::from_fn(|col| {
            std::array::from_fn(|row| {
                let delta = f64::from(u8::from(col == c));
                let x = 4.0 / r2 * self.t(row, col, c)
                    - delta * b[row]
                    - j.col(c)[row] * b[col]
                    - 4.0 / r2 * m[row] * self.s(col, c)
                    + delta * m[row] * w;
                -cc * b[c] * j.col(col)[row] + cc * x
            })
        }))
    }

    /// ∇ of the largest real part of ∇x̄'s eigenvalues, at the eigenvalue `ev`.
    fn eigenvalue_gradient(&self, mean: &MeanDistance, ev: Complex, support: f32) -> DVec3 {
        let Some(slope) = EigenvalueSlope::at(&mean.jacobian, ev) else {
            return DVec3::ZERO;
        };
        DVec3::from_array(std::array::from_fn(|c| {
            slope.derivative(&self.jacobian_derivative(mean, support, c))
        }))
    }
}

/// d Re λ for the eigenvalue `ev` of `j` when `j` changes by `d`: differentiating the
/// characteristic polynomial p(λ) = λ³ − tr λ² + M λ − det at fixed λ gives
/// dλ = −(∂p/∂J : dJ) / p'(λ), with ∂p/∂J = (λ tr − λ²) I − λ Jᵀ − cof J. What does not
/// depend on `d` is computed once for the three directions of a gradient.
struct EigenvalueSlope<'a> {
    j: &'a DMat3,
    ev: Complex,
    trace: f64,
    /// p'(λ).
    slope: Complex,
    cof: DMat3,
}

impl<'a> EigenvalueSlope<'a> {
    /// `None` at a repeated eigenvalue, where λ has no derivative.
    fn at(j: &'a DMat3, ev: Complex) -> Option<EigenvalueSlope<'a>> {
        let (trace, minors) = trace_and_minors(j);
        let slope = ev
            .mul(ev)
            .scale(3.0)
            .add(ev.scale(-2.0 * trace))
            .add(Complex::real(minors));
        if slope.norm2() < 1e-24 {
            return None;
        }
        let cof = DMat3::from_cols(
            j.y_axis.cross(j.z_axis),
            j.z_axis.cross(j.x_axis),
            j.x_axis.cross(j.y_axis),
        );
        Some(EigenvalueSlope {
            j,
            ev,
            trace,
            slope,
            cof,
        })
    }

    fn derivative(&self, d: &DMat3) -> f64 {
        let (ev, trace) = (self.ev, self.trace);
        let trace_d = d.x_axis.x + d.y_axis.y + d.z_axis.z;
        let jd = *self.j * *d;
        let trace_jd = jd.x_axis.x + jd.y_axis.y + jd.z_axis.z;
        let cof_d = (0..3).map(|k| self.cof.col(k).dot(d.col(k))).sum::<f64>();
        let dp = ev
            .scale(trace)
            .sub(ev.mul(ev))
            .scale(trace_d)
            .sub(ev.scale(trace_jd))
            .sub(Complex::real(cof_d));
        -dp.div(self.slope).re
    }
}

/// Just enough complex arithmetic for an eigenvalue of a real 3×3 matrix.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Complex {
    re: f64,
    im: f64,
}

impl Complex {
    fn real(re: f64) -> Complex {
        Complex { re, im: 0.0 }
    }
    fn add(self, o: Complex) -> Complex {
        Complex {
            re: self.re + o.re,
            im: self.im + o.im,
        }
    }
    fn sub(self, o: Complex) -> Complex {
        self.add(o.scale(-1.0))
    }
    fn scale(self, s: f64) -> Complex {
        Complex {
            re: self.re * s,
            im: self.im * s,
        }
    }
    fn mul(self, o: Complex) -> Complex {
        Complex {
            re: self.re * o.re - self.im * o.im,
            im: self.re * o.im + self.im * o.re,
        }
    }
    fn norm2(self) -> f64 {
        self.re * self.re + self.im * self.im
    }
    fn div(self, o: Complex) -> Complex {
        let n = o.norm2();
        Complex {
            re: (self.re * o.re + self.im * o.im) / n,
            im: (self.im * o.re - self.re * o.im) / n,
        }
    }
}

/// The trace and the sum of the principal 2×2 minors.
fn trace_and_minors(a: &DMat3) -> (f64, f64) {
    let trace = a.x_axis.x + a.y_axis.y + a.z_axis.z;
    let minors = a.x_axis.x * a.y_axis.y - a.y_axis.x * a.x_axis.y + a.x_axis.x * a.z_axis.z
        - a.z_axis.x * a.x_axis.z
        + a.y_axis.y * a.z_axis.z
        - a.z_axis.y * a.y_axis.z;
    (trace, minors)
}

/// The eigenvalue with the largest real part of a 3×3 matrix, from its characteristic cubic.
/// ∇x̄ is not symmetric, so a complex pair may occur; its real part then competes too.
fn largest_eigenvalue(a: &DMat3) -> Complex {
    let (trace, minors) = trace_and_minors(a);
    let det = a.determinant();
    // λ³ − trace λ² + minors λ − det = 0; with λ = μ + trace/3: μ³ + pμ + q = 0.
    let shift = trace / 3.0;
    let p = minors - trace * trace / 3.0;
    let q = -2.0 * trace.powi(3) / 27.0 + trace * minors / 3.0 - det;
    let discriminant = (q / 2.0).powi(2) + (p / 3.0).powi(3);
    let mu = if discriminant > 0.0 {
        let s = discriminant.sqrt();
        let (u, v) = ((-q / 2.0 + s).cbrt(), (-q / 2.0 - s).cbrt());
        let real = u + v;
        // The complex pair is −real/2 ± i √3/2 (u − v).
        if real >= -real / 2.0 {
            Complex::real(real)
        } else {
            Complex {
                re: -real / 2.0,
                im: 3f64.sqrt() / 2.0 * (u - v),
            }
        }
    } else if p < 0.0 {
        let r = (-p / 3.0).sqrt();
        let cos = (-q / (2.0 * r.powi(3))).clamp(-1.0, 1.0);
        Complex::real(2.0 * r * (cos.acos() / 3.0).cos())
    } else {
        Complex::real(0.0)
    };
    mu.add(Complex::real(shift))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn near(points: &[Vec3]) -> Neighbourhood {
        let mut n = Neighbourhood::default();
        n.set(Vec3::ZERO, points);
        n
    }

    /// `n` points on a golden-angle spiral, waving in z, within `radii` of the origin.
    fn spiral(n: usize, radii: Vec3) -> Vec<Vec3> {
        (0..n)
            .map(|i| {
                let a = i as f32 * 2.399;
                Vec3::new(a.cos(), a.sin(), (i as f32 * 0.37).sin()) * radii
            })
            .collect()
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
        assert!((largest_eigenvalue(&diag).re - 3.0).abs() < 1e-9);
        // Rotation by 90° about z scaled by 2, plus 0.5 on z: eigenvalues ±2i and 0.5.
        let rot = DMat3::from_cols(
            DVec3::new(0.0, 2.0, 0.0),
            DVec3::new(-2.0, 0.0, 0.0),
            DVec3::new(0.0, 0.0, 0.5),
        );
        assert!((largest_eigenvalue(&rot).re - 0.5).abs() < 1e-9);
        let triple = DMat3::from_diagonal(DVec3::splat(1.5));
        assert!((largest_eigenvalue(&triple).re - 1.5).abs() < 1e-6);
    }

    #[test]
    fn eigenvalue_derivative_matches_finite_differences() {
        let d = DMat3::from_cols(
            DVec3::new(0.3, -0.7, 0.2),
            DVec3::new(0.5, 0.1, -0.4),
            DVec3::new(-0.2, 0.6, 0.9),
        );
        // A real largest eigenvalue, and a matrix whose complex pair has the largest real part.
        let real = DMat3::from_cols(
            DVec3::new(1.0, 0.4, 0.1),
            DVec3::new(-0.3, 2.0, 0.5),
            DVec3::new(0.2, 0.1, 0.5),
        );
        let rot = DMat3::from_cols(
            DVec3::new(1.0, 2.0, 0.1),
            DVec3::new(-2.0, 1.0, 0.3),
            DVec3::new(0.2, -0.1, -0.5),
        );
        for (j, complex) in [(real, false), (rot, true)] {
            let ev = largest_eigenvalue(&j);
            assert_eq!(ev.im != 0.0, complex, "{ev:?}");
            let h = 1e-6;
            let fd = (largest_eigenvalue(&(j + d * h)).re - largest_eigenvalue(&(j - d * h)).re)
                / (2.0 * h);
            let exact = EigenvalueSlope::at(&j, ev).unwrap().derivative(&d);
            assert!((exact - fd).abs() < 1e-6, "{exact} vs {fd}");
        }
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
    fn lane_sums_are_the_same_on_every_path() {
        use crate::neighbours::lane_sums::tests::on_every_path;
        let n = near(&spiral(203, Vec3::new(2.3, 2.1, 2.5)));
        let x = Vec3::new(0.7, -0.4, 1.1);
        let sums = on_every_path(|| {
            (
                ssp07_sums(&n, x, 1.0 / 16.0).map(f32::to_bits),
                ssp07_gradient_sums(&n, x, 1.0 / 16.0).map(f32::to_bits),
            )
        });
        for (path, s) in &sums {
            assert_eq!(s, &sums[0].1, "{path:?}");
        }
    }

    #[test]
    fn settled_signs_are_the_values_signs_beyond_the_margin() {
        let f = field();
        let mut next = crate::tests::common::uniform(3);
        let mut settled = [0; 2];
        for (n, radii) in [
            (60, Vec3::new(2.3, 2.1, 2.5)),
            (200, Vec3::new(3.0, 3.0, 1.0)),
            (12, Vec3::splat(1.5)),
        ] {
            let n = near(&spiral(n, radii));
            for _ in 0..3000 {
                let x =
                    (crate::tests::common::uniform_point(&mut next) * 2.0 - 1.0) * (radii + 2.0);
                let margin = next() * 0.5;
                let v = f.value(&n, x);
                match f.value_or_sign(&n, x, margin) {
                    Sampled::Value(s) => assert_eq!(s.to_bits(), v.to_bits(), "at {x}"),
                    Sampled::Beyond { inside } => {
                        assert_eq!(inside, v < 0.0, "at {x}: {v}");
                        assert!(v.abs() > margin, "at {x}: {v} within {margin}");
                        settled[usize::from(inside)] += 1;
                    }
                }
            }
        }
        // Both sides get settled, and often.
        assert!(settled.iter().all(|&k| k > 300), "{settled:?}");
    }

    #[test]
    fn scattered_sums_give_the_gathered_value() {
        let f = field();
        let pts = spiral(60, Vec3::new(2.3, 2.1, 2.5));
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
            let (a, b) = (f.value_of(&s), f.value(&n, x));
            assert!((a - b).abs() < 1e-5, "at {x}: scatter {a}, gather {b}");
        }
    }

    #[test]
    fn jacobian_matches_finite_differences_of_the_mean() {
        let pts = spiral(40, Vec3::new(1.3, 1.1, 1.5));
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
