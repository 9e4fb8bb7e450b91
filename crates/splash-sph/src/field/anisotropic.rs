//! The anisotropic kernels of Yu & Turk 2010, as Akinci et al. 2012 (Sec. 5) compare them with
//! SSP07: every particle's kernel is an ellipsoid fitted to its neighbours by weighted PCA, and
//! centred on its Laplacian-smoothed position.
//!
//! With the neighbourhood radius h and w_ij = 1 − (|x_i − x_j|/h)³ inside it:
//! - smoothed centres x̄_i = (1 − λ) x_i + λ Σ_j w_ij x_j / Σ_j w_ij (λ = 0.3 as in Akinci);
//! - C_i = Σ_j w_ij (x_j − x_i^w)(x_j − x_i^w)ᵀ / Σ_j w_ij about the weighted mean x_i^w, with
//!   eigen-decomposition R diag(σ1 ≥ σ2 ≥ σ3) Rᵀ;
//! - Σ̃ = k_s diag(σ1, max(σ2, σ1/k_r), max(σ3, σ1/k_r)) for more than N_ε neighbours, else k_n I;
//!   G_i = (1/h) R Σ̃⁻¹ Rᵀ;
//! - φ(x) = iso − Σ_j V_j σ det(G_j) P(|G_j (x − x̄_j)|), P the cubic spline of support 1,
//!   V_j = m/ρ_j the particle volumes of the `density` field (cubic spline of support 2r on
//!   the original positions). Inside the fluid the kernels sum to about 1, as the density
//!   field's do; a lone particle (V = π r³, kernel of radius k_n·h = 2r by default) peaks at
//!   exactly 1, so splashes stay visible.
//!
//! Units. YT10's k_s = 1400 scales C in their world units so that ‖k_s C‖ ≈ 1 for a full
//! neighbourhood; with our r ~ 0.005–0.01 it would shrink interior kernels to a tenth of h. Here
//! C is measured in units of h², which makes k_s dimensionless: a full neighbourhood has
//! σ ≈ 0.15 h² (continuum value ∫(1 − s³)s⁴ ds / 3∫(1 − s³)s² ds; 0.145 h² on a cubic lattice at
//! h = 2r, 0.1506 h² at h = 4r), so the default k_s = 1/0.15 ≈ 6.7 gives an interior particle
//! Σ̃ ≈ I, G ≈ I/h and a kernel reaching h, as YT10 intend. A lone particle gets k_n I, a
//! sphere of radius k_n·h.
//!
//! N_ε = 25 counts neighbours within h. At h = 2r a cubic lattice gives an interior particle
//! only 26 neighbours and a particle on a flat face 17, so every surface particle would keep
//! the isotropic k_n kernel and the method would do nothing; hence the default h = 4r (about
//! 260 interior neighbours, 130 on a face, 48 in a one-layer sheet of spacing r), where N_ε
//! again singles out splashes, as in YT10 (whose h was twice the SPH smoothing radius).

use std::f32::consts::PI;

use crate::error::Result;
use glam::{Mat3, Vec3};
use serde::{Deserialize, Serialize};

use super::cubic_spline::{cubic_spline, cubic_spline_slope_over_q};
use super::density::particle_volumes;
use super::radial_kernel::RadialKernel;
use super::scalar_field::{Fitted, ScalarField};
use crate::length::Length;
use crate::neighbours::handler_array::HandlerArray;
use crate::neighbours::lane_sums::lane_sums;
use crate::neighbours::neighbourhood::{Neighbourhood, map_particles};

/// `[field] kind = "anisotropic"`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AnisotropicConfig {
    /// Neighbourhood radius h of the smoothing and of the PCA; also the kernel scale.
    pub neighbourhood: Length,
    /// Laplacian smoothing λ of the kernel centres (Akinci 0.3; YT10 0.9–1).
    pub smoothing: f32,
    /// Largest ratio σ1/σk of the kernel's axes (YT10: 4).
    pub k_r: f32,
    /// Scale of the covariance, in units of h² (see the module notes: 1/0.15).
    pub k_s: f32,
    /// A splash particle's kernel radius, in units of h (YT10: 0.5).
    pub k_n: f32,
    /// Particles with at most this many neighbours within h get the isotropic kernel (YT10: 25).
    pub n_eps: u32,
    /// Support of the SPH kernel that gives the particle volumes m/ρ (as `density`).
    pub volume_support: Length,
    /// Surface where the kernel sum falls to this (about 1 inside).
    pub iso: f32,
}

impl Default for AnisotropicConfig {
    fn default() -> Self {
        AnisotropicConfig {
            neighbourhood: Length::Spacings(4.0),
            smoothing: 0.3,
            k_r: 4.0,
            k_s: 1.0 / 0.15,
            k_n: 0.5,
            n_eps: 25,
            volume_support: Length::Spacings(2.0),
            iso: 0.6,
        }
    }
}

impl AnisotropicConfig {
    /// Checks the ranges the TOML types cannot express, naming the key.
    pub fn validate(&self) -> Result<()> {
        self.neighbourhood.check_positive("field.neighbourhood")?;
        self.volume_support.check_positive("field.volume_support")?;
        if !(0.0..=1.0).contains(&self.smoothing) {
            bail_config!(
                "field.smoothing must lie between 0 and 1, got {}",
                self.smoothing
            );
        }
        if !(self.k_r >= 1.0 && self.k_r.is_finite()) {
            bail_config!("field.k_r must be at least 1, got {}", self.k_r);
        }
        for (key, v) in [("field.k_s", self.k_s), ("field.k_n", self.k_n)] {
            if !(v > 0.0 && v.is_finite()) {
                bail_config!("{key} must be positive, got {v}");
            }
        }
        if !(self.iso > 0.0 && self.iso < 1.0) {
            bail_config!(
                "field.iso must lie strictly between 0 and 1, got {}",
                self.iso
            );
        }
        Ok(())
    }

    pub(crate) fn resolve(&self, r: f32) -> Anisotropic {
        let h = self.neighbourhood.resolve(r);
        Anisotropic {
            h,
            volume_support: self.volume_support.resolve(r),
            smoothing: self.smoothing,
            k_r: self.k_r,
            k_s: self.k_s,
            k_n: self.k_n,
            n_eps: self.n_eps,
            iso: self.iso,
            // Until fitted: the reach of an interior kernel (Σ̃ ≈ I) or of a lone one.
            support: h * self.k_n.max(1.0),
        }
    }
}

#[derive(Debug, Clone)]
pub struct Anisotropic {
    pub h: f32,
    pub volume_support: f32,
    pub smoothing: f32,
    pub k_r: f32,
    pub k_s: f32,
    pub k_n: f32,
    pub n_eps: u32,
    pub iso: f32,
    /// The farthest any kernel reaches; after [`fit`](ScalarField::fit), over this frame's.
    pub support: f32,
}

/// The channels of a fitted kernel: G's entries xx, yy, zz, xy, xz, yz, V σ det G, and its
/// reach.
const CHANNELS: usize = 8;
const REACH: usize = 7;

/// One particle's kernel: smoothed centre, G, and how far it reaches.
pub struct Kernel {
    pub centre: Vec3,
    pub g: Mat3,
    pub det: f32,
    pub reach: f32,
}

impl Anisotropic {
    /// The kernel of the particle at `x` (relative to `near.anchor`), from its neighbours in
    /// `near` (which holds all within h, the particle itself included).
    pub fn kernel(&self, near: &Neighbourhood, x: Vec3) -> Kernel {
        let inv_h = 1.0 / self.h;
        let [sw, mx, my, mz, sxx, syy, szz, sxy, sxz, syz, count] = moments(near, x, inv_h);
        let (m, s) = (Vec3::new(mx, my, mz), [sxx, syy, szz, sxy, sxz, syz]);
        // `p` itself is in `near`, so sw ≥ 1.
        let m = m / sw;
        let c = [
            s[0] / sw - m.x * m.x,
            s[1] / sw - m.y * m.y,
            s[2] / sw - m.z * m.z,
            s[3] / sw - m.x * m.y,
            s[4] / sw - m.x * m.z,
            s[5] / sw - m.y * m.z,
        ];
        let centre = near.anchor + x + self.smoothing * m * self.h;
        let neighbours = count as u32 - 1;
        let (axes, sigma) = symmetric_eigen(c);
        // Σ̃ in units of h², largest first.
        let stretch = if neighbours > self.n_eps && sigma[0] > 0.0 {
            let floor = sigma[0] / self.k_r;
            [sigma[0], sigma[1].max(floor), sigma[2].max(floor)].map(|v| self.k_s * v)
        } else {
            [self.k_n; 3]
        };
        // G = (1/h) R Σ̃⁻¹ Rᵀ.
        let inv = Mat3::from_diagonal(Vec3::from(stretch.map(|v| 1.0 / v)));
        let g = axes * inv * axes.transpose() * inv_h;
        let det = inv_h.powi(3) / (stretch[0] * stretch[1] * stretch[2]);
        let reach = self.h * stretch.iter().fold(0.0f32, |a, &b| a.max(b));
        Kernel {
            centre,
            g,
            det,
            reach,
        }
    }

    /// Every particle's kernel, in handler order.
    pub fn kernels(&self, handlers: &HandlerArray) -> Vec<Kernel> {
        map_particles(handlers, self.h, |near, x| self.kernel(near, x))
    }
}

// Σ w, Σ w d, Σ w d dᵀ (xx, yy, zz, xy, xz, yz) and the count of particles within h, with
// d = (x_j − x)/h and w = 1 − |d|³ inside h.
lane_sums! {
    fn moments(inv_h: f32) -> [11] |dx, dy, dz| {
        let (dx, dy, dz) = (dx * inv_h, dy * inv_h, dz * inv_h);
        let q = (dx * dx + dy * dy + dz * dz).sqrt();
        let w = (1.0 - q * q * q).max(0.0);
        let (wx, wy, wz) = (w * dx, w * dy, w * dz);
        [
            w,
            wx,
            wy,
            wz,
            wx * dx,
            wy * dy,
            wz * dz,
            wx * dy,
            wx * dz,
            wy * dz,
            f32::from(u8::from(w > 0.0)),
        ]
    }
}

/// Eigenvectors (columns) and eigenvalues, largest first, of the symmetric matrix with entries
/// xx, yy, zz, xy, xz, yz, by cyclic Jacobi rotations in f64.
pub fn symmetric_eigen(c: [f32; 6]) -> (Mat3, [f32; 3]) {
    let [xx, yy, zz, xy, xz, yz] = c.map(f64::from);
    let mut a = [[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]];
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0f64]];
    for _sweep in 0..32 {
        let off = a[0][1].powi(2) + a[0][2].powi(2) + a[1][2].powi(2);
        let scale = a[0][0].powi(2) + a[1][1].powi(2) + a[2][2].powi(2);
        if off <= 1e-30 * scale || off == 0.0 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q] == 0.0 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let cs = 1.0 / (t * t + 1.0).sqrt();
            let sn = t * cs;
            // a ← Jᵀ a J with J the rotation in the (p, q) plane.
            for row in &mut a {
                let (akp, akq) = (row[p], row[q]);
                row[p] = cs * akp - sn * akq;
                row[q] = sn * akp + cs * akq;
            }
            let (rp, rq) = (a[p], a[q]);
            for k in 0..3 {
                a[p][k] = cs * rp[k] - sn * rq[k];
                a[q][k] = sn * rp[k] + cs * rq[k];
            }
            for row in &mut v {
                let (vp, vq) = (row[p], row[q]);
                row[p] = cs * vp - sn * vq;
                row[q] = sn * vp + cs * vq;
            }
        }
    }
    let mut order = [0, 1, 2];
    order.sort_by(|&i, &j| a[j][j].total_cmp(&a[i][i]));
    let col = |i: usize| Vec3::new(v[0][i] as f32, v[1][i] as f32, v[2][i] as f32);
    (
        Mat3::from_cols(col(order[0]), col(order[1]), col(order[2])),
        order.map(|i| a[i][i] as f32),
    )
}

impl ScalarField for Anisotropic {
    fn support(&self) -> f32 {
        self.support
    }

    fn radial_kernel(&self) -> RadialKernel {
        // Not the fitted ellipsoids (their fit is a pass of its own, and a splash particle's
        // reaches k_n·h): the kernel of an interior particle, Σ̃ ≈ I, a cubic spline of radius h.
        RadialKernel::CubicSpline { support: self.h }
    }

    /// The kernels of this frame, on a handler array over their smoothed centres, with G and
    /// V σ det G as channels.
    fn fit(&self, handlers: &HandlerArray) -> Option<Result<Fitted>> {
        let kernels = self.kernels(handlers);
        let support = kernels.iter().fold(0.0f32, |a, k| a.max(k.reach));
        let volumes = particle_volumes(handlers, self.volume_support);
        let mut channels: Vec<Vec<f32>> = (0..CHANNELS)
            .map(|_| Vec::with_capacity(kernels.len()))
            .collect();
        for (k, v) in kernels.iter().zip(volumes) {
            let g = k.g;
            let values = [
                g.x_axis.x,
                g.y_axis.y,
                g.z_axis.z,
                g.y_axis.x,
                g.z_axis.x,
                g.z_axis.y,
                v * 8.0 / PI * k.det,
                k.reach,
            ];
            for (c, v) in channels.iter_mut().zip(values) {
                c.push(v);
            }
        }
        let centres: Vec<Vec3> = kernels.iter().map(|k| k.centre).collect();
        Some(
            HandlerArray::with_channels(&centres, support / 2.0, channels).map(|handlers| Fitted {
                field: Box::new(Anisotropic {
                    support,
                    ..self.clone()
                }),
                handlers,
            }),
        )
    }

    fn reach_channel(&self) -> Option<usize> {
        Some(REACH)
    }

    /// Needs the channels of [`fit`](ScalarField::fit) in `near`.
    fn value(&self, near: &Neighbourhood, x: Vec3) -> f32 {
        let [gxx, gyy, gzz, gxy, gxz, gyz, w, _] =
            <&[Vec<f32>; CHANNELS]>::try_from(near.channels.as_slice())
                .expect("the anisotropic field samples fitted kernels only");
        let mut sum = 0.0;
        for i in 0..near.len() {
            let (dx, dy, dz) = (near.x[i] - x.x, near.y[i] - x.y, near.z[i] - x.z);
            let gx = gxx[i] * dx + gxy[i] * dy + gxz[i] * dz;
            let gy = gxy[i] * dx + gyy[i] * dy + gyz[i] * dz;
            let gz = gxz[i] * dx + gyz[i] * dy + gzz[i] * dz;
            sum += w[i] * cubic_spline((gx * gx + gy * gy + gz * gz).sqrt());
        }
        self.iso - sum
    }

    /// Σ_j w_j P'(q)/q · G_j g_j, with g_j = G_j (x_j − x) and q = |g_j|, as ∇_x q = −G g/q
    /// (G symmetric).
    fn gradient(&self, near: &Neighbourhood, x: Vec3) -> Vec3 {
        let [gxx, gyy, gzz, gxy, gxz, gyz, w, _] =
            <&[Vec<f32>; CHANNELS]>::try_from(near.channels.as_slice())
                .expect("the anisotropic field samples fitted kernels only");
        let mut sum = Vec3::ZERO;
        for i in 0..near.len() {
            let (dx, dy, dz) = (near.x[i] - x.x, near.y[i] - x.y, near.z[i] - x.z);
            let gx = gxx[i] * dx + gxy[i] * dy + gxz[i] * dz;
            let gy = gxy[i] * dx + gyy[i] * dy + gyz[i] * dz;
            let gz = gxz[i] * dx + gyz[i] * dy + gzz[i] * dz;
            let q = (gx * gx + gy * gy + gz * gz).sqrt();
            let s = w[i] * cubic_spline_slope_over_q(q);
            sum += s * Vec3::new(
                gxx[i] * gx + gxy[i] * gy + gxz[i] * gz,
                gxy[i] * gx + gyy[i] * gy + gyz[i] * gz,
                gxz[i] * gx + gyz[i] * gy + gzz[i] * gz,
            );
        }
        sum
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lattice(n: i32, r: f32, keep: impl Fn(Vec3) -> bool) -> Vec<Vec3> {
        let mut out = Vec::new();
        for z in -n..=n {
            for y in -n..=n {
                for x in -n..=n {
                    let p = Vec3::new(x as f32, y as f32, z as f32) * r;
                    if keep(p) {
                        out.push(p);
                    }
                }
            }
        }
        out
    }

    #[test]
    fn jacobi_diagonalises_a_rotated_diagonal_matrix() {
        let r = Mat3::from_rotation_y(0.4) * Mat3::from_rotation_x(1.1);
        let a = r * Mat3::from_diagonal(Vec3::new(0.5, 3.0, 1.0)) * r.transpose();
        let c = [
            a.x_axis.x, a.y_axis.y, a.z_axis.z, a.y_axis.x, a.z_axis.x, a.z_axis.y,
        ];
        let (v, s) = symmetric_eigen(c);
        assert!((s[0] - 3.0).abs() < 1e-5 && (s[1] - 1.0).abs() < 1e-5);
        assert!((s[2] - 0.5).abs() < 1e-5, "{s:?}");
        let back = v * Mat3::from_diagonal(Vec3::from(s)) * v.transpose();
        assert!(back.abs_diff_eq(a, 1e-5), "{back} vs {a}");
        // A diagonal matrix with equal entries needs no rotation at all.
        let (v, s) = symmetric_eigen([2.0, 2.0, 2.0, 0.0, 0.0, 0.0]);
        assert_eq!((v, s), (Mat3::IDENTITY, [2.0; 3]));
    }

    /// The units of the module notes: an interior lattice particle's G is about I/h (its
    /// kernel reaches about h), a particle of a one-layer sheet gets a flat kernel, a lone
    /// particle a sphere of k_n·h.
    #[test]
    fn kernels_have_the_sizes_the_normalisation_promises() {
        let r = 0.01;
        let field = AnisotropicConfig::default().resolve(r);
        let h = field.h;
        let mut near = Neighbourhood::default();
        let ball = lattice(6, r, |p| p.length() <= 6.0 * r);
        near.set(Vec3::ZERO, &ball);
        let k = field.kernel(&near, Vec3::ZERO);
        // Measured: diagonal 0.996/h, off-diagonal 0 (σ = 0.1506 h² on the lattice at h = 4r).
        let g = k.g * h;
        for i in 0..3 {
            assert!((g.col(i)[i] - 1.0).abs() < 0.05, "{g}");
        }
        assert!((k.reach / h - 1.0).abs() < 0.05, "reach {}", k.reach / h);
        assert!(k.centre.length() < 1e-9, "{}", k.centre);

        let sheet = lattice(6, r, |p| p.z == 0.0);
        near.set(Vec3::ZERO, &sheet);
        let k = field.kernel(&near, Vec3::ZERO);
        let g = k.g * h;
        // Measured in-plane σ = 0.176 h² (2-D continuum 0.179): G·h = 0.854 in the plane, axes
        // of 1.17h; across it k_r = 4 times that, 0.29h.
        assert!((g.z_axis.z - 4.0 * g.x_axis.x).abs() < 1e-4, "{g}");
        assert!(g.x_axis.x > 0.83 && g.x_axis.x < 0.88, "{g}");
        assert!(g.x_axis.y.abs() < 1e-4 && g.z_axis.x.abs() < 1e-4, "{g}");

        near.set(Vec3::ZERO, &[Vec3::ZERO, Vec3::X * r]);
        let k = field.kernel(&near, Vec3::ZERO);
        assert!((k.g * h).abs_diff_eq(Mat3::IDENTITY * 2.0, 1e-5));
        assert!((k.reach - 0.5 * h).abs() < 1e-6);
        // Smoothed towards the neighbour: λ · its weighted mean offset.
        let w = 1.0 - 0.25f32.powi(3);
        let expected = 0.3 * r * w / (1.0 + w);
        assert!((k.centre.x - expected).abs() < 1e-7, "{}", k.centre.x);
    }
}
