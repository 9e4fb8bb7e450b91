//! Every field's analytic gradient against central differences of its value.

use crate::field::{FieldConfig, ScalarField};
use crate::neighbours::handler_array::HandlerArray;
use crate::neighbours::neighbourhood::Neighbourhood;
use crate::tests::common::{Jitter, lattice_ball};
use glam::Vec3;

/// Spacing 1, so that values and gradients are of order 1 and f32 rounding stays far below the
/// tolerance.
const R: f32 = 1.0;
/// Finite-difference step: small against the kernels (≥ 0.75r), so that the central
/// difference's error H²f‴/6 is far below the tolerance.
const H: f32 = 2e-3;
/// |∇ − FD| ≤ REL·|FD| + ABS, plus the f32 rounding of the values in the difference quotient.
const REL: f32 = 0.01;
const ABS: f32 = 2e-3;

/// A jittered ball with a thin jittered sheet on top and a few lone particles: interior,
/// flat surface, thin sheet and splash, where SSP07's eigenvalue term is active.
fn particles() -> Vec<Vec3> {
    let mut jitter = Jitter::new(11);
    let mut out: Vec<Vec3> = lattice_ball(Vec3::ZERO, 5.0 * R, R)
        .into_iter()
        .map(|p| p + jitter.vec3() * 0.3 * R)
        .collect();
    for y in -6..=6 {
        for x in -6..=6 {
            let p = Vec3::new(x as f32 * 1.2, y as f32 * 1.2, 7.5) * R;
            out.push(p + jitter.vec3() * 0.4 * R);
        }
    }
    out.extend([
        Vec3::new(9.0, 0.0, 0.0),
        Vec3::new(9.0, 1.3, 0.5),
        Vec3::new(-8.0, -3.0, 2.0),
    ]);
    out
}

struct Probe<'a> {
    field: &'a dyn ScalarField,
    handlers: &'a HandlerArray,
    near: Neighbourhood,
}

impl Probe<'_> {
    fn value(&mut self, x: Vec3) -> f32 {
        self.gather(x);
        self.field.value(&self.near, x - self.near.anchor)
    }

    fn gradient(&mut self, x: Vec3) -> Vec3 {
        self.gather(x);
        self.field.gradient(&self.near, x - self.near.anchor)
    }

    fn gather(&mut self, x: Vec3) {
        let reach = self.field.support();
        self.near
            .gather_box(self.handlers, x, x, reach, self.field.reach_channel());
    }

    /// Central difference along `axis`, or None where the field has a kink within the step
    /// (SSP07's clamp at t_high, two eigenvalues crossing, a kernel's cut-off) and so no
    /// derivative to compare with. A smooth field's one-sided differences part by H·f'', twice
    /// what they do at step H/2; across a kink by about the jump in slope at both steps.
    fn central_difference(&mut self, x: Vec3, axis: usize) -> Option<f32> {
        let e = Vec3::AXES[axis];
        let mut v = |t: f32| self.value(x + e * t);
        let (mid, lo, hi, lo2, hi2) = (v(0.0), v(-H), v(H), v(-H / 2.0), v(H / 2.0));
        let bend = (hi - 2.0 * mid + lo) / H;
        let bend2 = (hi2 - 2.0 * mid + lo2) / (H / 2.0);
        let slope = (hi - lo) / (2.0 * H);
        ((bend - 2.0 * bend2).abs() <= REL * slope.abs() + 4.0 * noise(mid)).then_some(slope)
    }
}

/// What f32 rounding of values of size |v| (about 1e-6 of them) adds to a difference quotient.
fn noise(v: f32) -> f32 {
    1e-6 * (1.0 + v.abs()) / H
}

#[test]
fn every_gradient_matches_central_differences_of_the_value() {
    let particles = particles();
    for kind in FieldConfig::KINDS {
        let field = FieldConfig::named(kind).unwrap().build(R);
        let mut handlers = HandlerArray::new(&particles, 2.0 * R).unwrap();
        handlers.channels = field.particle_channels(&handlers);
        let fitted = field.fit(&handlers).transpose().unwrap();
        let (field, handlers) = match &fitted {
            Some(f) => (f.field.as_ref(), &f.handlers),
            None => (field.as_ref(), &handlers),
        };
        let mut probe = Probe {
            field,
            handlers,
            near: Neighbourhood::default(),
        };
        let mut jitter = Jitter::new(3);
        let (mut compared, mut kinks, mut active) = (0, 0, 0);
        for i in 0..400 {
            // Points within 1.5r of every kind of particle: interior, surface, sheet, splash.
            let x = particles[i * 7919 % particles.len()] + jitter.vec3() * 3.0 * R;
            let g = probe.gradient(x);
            for axis in 0..3 {
                let Some(fd) = probe.central_difference(x, axis) else {
                    kinks += 1;
                    continue;
                };
                compared += 1;
                active += usize::from(fd != 0.0);
                let tolerance = REL * fd.abs() + ABS + 2.0 * noise(probe.value(x));
                assert!(
                    (g[axis] - fd).abs() <= tolerance,
                    "{kind} at {x}, axis {axis}: gradient {g}, central difference {fd}"
                );
            }
        }
        // The comparison is not vacuous: most points are smooth, many see particles.
        assert!(
            kinks * 20 < compared,
            "{kind}: {kinks} kinks, {compared} compared"
        );
        assert!(
            active * 2 > compared,
            "{kind}: only {active} of {compared} non-zero"
        );
    }
}
