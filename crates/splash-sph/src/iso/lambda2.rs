//! The λ2 vortex criterion (Jeong & Hussain 1995; the Marching Correctors' dam break, Fig. 7 and
//! Table III): per particle, the middle eigenvalue of S² + Ω², S and Ω the symmetric and
//! antisymmetric parts of the SPH velocity gradient; λ2 < 0 inside vortex cores.

use glam::{DMat3, DVec3};

use super::sph_interpolant::Interpolant;

/// λ2_i at every particle from the velocity in channels `first..first + 3`, with the gradient
/// ∇v_i = Σ_j V_j (v_j − v_i) ⊗ ∇W(x_i − x_j): the difference form of the vorticity's SPH curl,
/// exact for a constant velocity and, in the bulk, the gradient of a linear one up to the
/// kernel sums' discretisation.
pub(crate) fn lambda2(it: &Interpolant, first: usize) -> Vec<f32> {
    it.velocity_sums(
        first,
        // Row a of the gradient is ∇v_a.
        |rows: &mut [DVec3; 3], grad, dv, volume| {
            let dv = dv * volume;
            rows[0] += grad * dv.x;
            rows[1] += grad * dv.y;
            rows[2] += grad * dv.z;
        },
        // The rows as columns: Gᵀ, whose S² + Ω² is G's.
        |rows| {
            middle_eigenvalue(&s2_plus_omega2(DMat3::from_cols(rows[0], rows[1], rows[2]))) as f32
        },
    )
}

/// S² + Ω² of a velocity gradient G: ((G + Gᵀ)² + (G − Gᵀ)²) / 4 = (G² + Gᵀ²) / 2, symmetric
/// and the same for G and Gᵀ, so the gradient's row or column convention does not matter.
pub(crate) fn s2_plus_omega2(g: DMat3) -> DMat3 {
    let g2 = g * g;
    (g2 + g2.transpose()) * 0.5
}

/// The middle eigenvalue of a symmetric 3×3 matrix in closed form (Smith 1961): the
/// eigenvalues are q + 2p cos(φ + 2πk/3) with q the trace's third, p the deviator's scale and
/// φ from its determinant; the middle one is the trace minus the other two. No iteration, so
/// the value is the same on every thread.
pub(crate) fn middle_eigenvalue(m: &DMat3) -> f64 {
    let (a00, a11, a22) = (m.x_axis.x, m.y_axis.y, m.z_axis.z);
    let (a01, a02, a12) = (m.y_axis.x, m.z_axis.x, m.z_axis.y);
    let off = a01 * a01 + a02 * a02 + a12 * a12;
    let q = (a00 + a11 + a22) / 3.0;
    let p2 = (a00 - q).powi(2) + (a11 - q).powi(2) + (a22 - q).powi(2) + 2.0 * off;
    if p2 == 0.0 {
        // A multiple of the identity.
        return q;
    }
    if off == 0.0 {
        // Diagonal: the median of the diagonal.
        return a00.max(a11).min(a00.min(a11).max(a22));
    }
    let p = (p2 / 6.0).sqrt();
    let b = (*m - DMat3::from_diagonal(DVec3::splat(q))) * (1.0 / p);
    let r = (b.determinant() / 2.0).clamp(-1.0, 1.0);
    let phi = r.acos() / 3.0;
    let largest = q + 2.0 * p * phi.cos();
    let smallest = q + 2.0 * p * (phi + 2.0 * std::f64::consts::FRAC_PI_3).cos();
    3.0 * q - largest - smallest
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The middle of three sorted values.
    fn median(mut e: [f64; 3]) -> f64 {
        e.sort_by(f64::total_cmp);
        e[1]
    }

    #[test]
    fn the_closed_form_matches_rotated_diagonal_matrices() {
        let rotation = DMat3::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 2.0);
        for e in [
            [3.0, -1.0, 0.5],
            [-2.0, -2.0, 5.0],
            [1e-3, 7.0, 7.0],
            [0.0, 0.0, -4.0],
            [-150.0, 20.0, 0.0],
        ] {
            let m = rotation * DMat3::from_diagonal(DVec3::from_array(e)) * rotation.transpose();
            let got = middle_eigenvalue(&m);
            let scale = e.iter().fold(0.0f64, |a, x| a.max(x.abs()));
            // A double eigenvalue (every planar flow's) costs acos half the digits, √ε: still
            // below f32's resolution, in which λ2 is kept.
            assert!((got - median(e)).abs() < 3e-8 * scale, "{e:?}: {got}");
            // The diagonal path, unrotated.
            let d = middle_eigenvalue(&DMat3::from_diagonal(DVec3::from_array(e)));
            assert_eq!(d, median(e), "{e:?}");
        }
        assert_eq!(
            middle_eigenvalue(&DMat3::from_diagonal(DVec3::splat(2.5))),
            2.5
        );
    }

    #[test]
    fn rotation_strain_and_shear_give_the_criterion_s_known_signs() {
        let w = 3.0;
        // Solid-body rotation about z: λ2 = −ω².
        let rotation = DMat3::from_cols(
            DVec3::new(0.0, w, 0.0),
            DVec3::new(-w, 0.0, 0.0),
            DVec3::ZERO,
        );
        assert!((middle_eigenvalue(&s2_plus_omega2(rotation)) + w * w).abs() < 1e-12);
        // Pure strain: λ2 = a².
        let strain = DMat3::from_diagonal(DVec3::new(w, -w, 0.0));
        assert!((middle_eigenvalue(&s2_plus_omega2(strain)) - w * w).abs() < 1e-12);
        // Simple shear: S² and Ω² cancel, λ2 = 0 (not a vortex).
        let shear = DMat3::from_cols(DVec3::ZERO, DVec3::new(w, 0.0, 0.0), DVec3::ZERO);
        assert_eq!(middle_eigenvalue(&s2_plus_omega2(shear)), 0.0);
    }
}
