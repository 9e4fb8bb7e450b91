//! λ2 of `splash iso` on analytic flows sampled on a particle lattice: a Lamb–Oseen vortex is
//! negative in its core and positive outside, changing sign at the radius of the largest speed;
//! uniform flow and simple shear are not vortices; the mesh does not depend on the threads.

use std::collections::BTreeMap;

use glam::Vec3;

use crate::config::Config;
use crate::io::Attribute;
use crate::iso::quantity::interpolant;
use crate::iso::{Derived, IsoRequest, extract};
use crate::length::Length;
use crate::mesh::topology::topology;

const R: f32 = 0.05;
/// Lamb–Oseen core radius: 4 spacings, so the kernel (support 2R) resolves the core.
const CORE: f32 = 0.2;
/// Circulation Γ.
const GAMMA: f32 = 1.0;

/// Particles on a lattice of spacing R filling [0, 1]² × [0, depth], each of volume R³, with the
/// velocity `v(x)`.
fn lattice(depth: f32, v: impl Fn(Vec3) -> Vec3) -> (Vec<Vec3>, BTreeMap<String, Attribute>) {
    let (n, nz) = ((1.0 / R).round() as i32, (depth / R).round() as i32);
    let positions: Vec<Vec3> = (0..=nz)
        .flat_map(|z| (0..=n).flat_map(move |y| (0..=n).map(move |x| (x, y, z))))
        .map(|(x, y, z)| Vec3::new(x as f32, y as f32, z as f32) * R)
        .collect();
    let count = positions.len();
    let attributes = BTreeMap::from([
        (
            "velocity".to_string(),
            Attribute::Vector(positions.iter().map(|&p| v(p)).collect()),
        ),
        (
            "mass".to_string(),
            Attribute::Scalar(vec![R * R * R; count]),
        ),
        ("density".to_string(), Attribute::Scalar(vec![1.0; count])),
    ]);
    (positions, attributes)
}

/// The Lamb–Oseen vortex about the vertical line through (0.5, 0.5): v_θ(ρ) = Γ/(2πρ)·(1 −
/// e^{−ρ²/c²}), times `along(z)`.
fn lamb_oseen(p: Vec3, along: impl Fn(f32) -> f32) -> Vec3 {
    let d = Vec3::new(p.x - 0.5, p.y - 0.5, 0.0);
    let rho = d.length();
    if rho == 0.0 {
        return Vec3::ZERO;
    }
    let speed = GAMMA / (2.0 * std::f32::consts::PI * rho) * (1.0 - (-(rho / CORE).powi(2)).exp());
    Vec3::new(-d.y, d.x, 0.0) / rho * speed * along(p.z)
}

/// The particles and their λ2, as `splash iso --lambda2` interpolates it (in the interpolant's
/// order).
fn lambda2_at_particles(
    positions: &[Vec3],
    mut attributes: BTreeMap<String, Attribute>,
) -> (Vec<Vec3>, Vec<f32>) {
    let request = IsoRequest {
        attribute: "velocity".into(),
        derived: Derived::Lambda2,
        level: 0.0,
    };
    let it = interpolant(
        positions,
        &mut attributes,
        &request,
        &[],
        2.0 * R,
        1.0,
        false,
    )
    .unwrap();
    let values = it.handlers.channels[it.channels.value].clone();
    (it.handlers.positions, values)
}

#[test]
fn a_lamb_oseen_vortex_is_negative_in_its_core_and_changes_sign_at_the_largest_speed() {
    let (positions, attributes) = lattice(0.4, |p| lamb_oseen(p, |_| 1.0));
    let (positions, l2) = lambda2_at_particles(&positions, attributes);
    // A planar vortex v_θ(ρ) has λ2 = −(v_θ/ρ)·dv_θ/dρ: negative while the speed grows, zero at
    // its peak, ρ* = 1.1209 c for Lamb–Oseen (the root of 1 + 2x² = e^{x²}, x = ρ/c).
    let peak = 1.120_906 * CORE;
    // The particles of the middle layer along the ray y = 0.5, x > 0.5, away from the walls.
    let ray: Vec<(f32, f32)> = positions
        .iter()
        .zip(&l2)
        .filter(|(p, _)| (p.z - 0.2).abs() < 1e-4 && (p.y - 0.5).abs() < 1e-4 && p.x > 0.5)
        .filter(|(p, _)| p.x < 1.0 - 2.0 * R)
        .map(|(p, &l)| (p.x - 0.5, l))
        .collect();
    assert!(ray.len() >= 7, "{ray:?}");
    // The axis, the strongest: a solid-body rotation at Ω = Γ/(2πc²), λ2 = −Ω². The kernel
    // sums make the SPH gradient a little smaller (measured: λ2 = 0.96 of −Ω²).
    let axis = l2[positions
        .iter()
        .position(|p| (*p - Vec3::new(0.5, 0.5, 0.2)).length() < 1e-4)
        .unwrap()];
    let omega = GAMMA / (2.0 * std::f32::consts::PI * CORE * CORE);
    let ratio = axis / (-omega * omega);
    assert!(
        (0.85..=1.0).contains(&ratio),
        "{axis} vs {}",
        -omega * omega
    );
    // Negative inside, positive beyond; one sign change, found by linear interpolation. The
    // SPH gradient is that of the kernel-smoothed velocity, whose peak moves outward by a
    // fraction of the support: measured 0.010 = 0.2 R here, within R/2 (the lattice's
    // resolution of the crossing).
    let inside: Vec<_> = ray.iter().filter(|(rho, _)| *rho < 0.8 * peak).collect();
    let outside: Vec<_> = ray.iter().filter(|(rho, _)| *rho > 1.3 * peak).collect();
    assert!(inside.iter().all(|(_, l)| *l < 0.0), "{ray:?}");
    assert!(
        !outside.is_empty() && outside.iter().all(|(_, l)| *l > 0.0),
        "{ray:?}"
    );
    let crossings: Vec<f32> = ray
        .windows(2)
        .filter(|w| (w[0].1 < 0.0) != (w[1].1 < 0.0))
        .map(|w| w[0].0 + (w[1].0 - w[0].0) * w[0].1 / (w[0].1 - w[1].1))
        .collect();
    assert_eq!(crossings.len(), 1, "{ray:?}");
    eprintln!(
        "λ2 changes sign at {} (analytic {peak}); axis {axis}, −ω² {}",
        crossings[0],
        -omega * omega
    );
    assert!(
        (crossings[0] - peak).abs() < 0.5 * R,
        "{} vs {peak}",
        crossings[0]
    );
}

#[test]
fn uniform_flow_and_simple_shear_are_not_vortices() {
    // Uniform: every v_j − v_i is zero, so λ2 is exactly 0.
    let (positions, attributes) = lattice(0.3, |_| Vec3::new(0.3, -1.0, 2.0));
    let (_, l2) = lambda2_at_particles(&positions, attributes);
    assert!(l2.iter().all(|&l| l == 0.0));
    // Simple shear v = (γy, 0, 0): S² = −Ω², λ2 = 0 up to rounding (γ² = 4 sets the scale);
    // the lattice's missing neighbours at the walls only scale ∂v_x/∂y, which keeps it 0.
    let gamma = 2.0;
    let (positions, attributes) = lattice(0.3, |p| Vec3::new(gamma * p.y, 0.0, 0.0));
    let (_, l2) = lambda2_at_particles(&positions, attributes);
    let worst = l2.iter().fold(0.0f32, |a, l| a.max(l.abs()));
    assert!(
        l2.iter().all(|&l| l >= -1e-5 * gamma * gamma),
        "worst {worst}"
    );
    assert!(worst < 1e-5 * gamma * gamma, "{worst}");
}

/// The vortex faded along z, so that its core λ2 < level is a closed cigar inside the box.
fn faded_vortex() -> (Vec<Vec3>, BTreeMap<String, Attribute>) {
    lattice(1.0, |p| {
        lamb_oseen(p, |z| (-((z - 0.5) / 0.2).powi(2)).exp())
    })
}

fn config(threads: usize) -> Config {
    Config {
        spacing: Some(R),
        cell: Length::Spacings(0.5),
        threads: Some(threads),
        ..Config::default()
    }
}

#[test]
fn the_vortex_core_is_one_closed_surface_the_same_for_one_and_two_threads() {
    let (positions, attributes) = faded_vortex();
    let request = IsoRequest {
        attribute: "v".into(),
        derived: Derived::Lambda2,
        level: -2.0,
    };
    let one = extract(&positions, attributes.clone(), &request, &config(1)).unwrap();
    let two = extract(&positions, attributes, &request, &config(2)).unwrap();
    assert_eq!(one.mesh, two.mesh);
    let t = topology(&one.mesh);
    assert!(t.is_closed_manifold(), "{t:?}");
    assert_eq!((t.components, t.euler_characteristic), (1, 2), "{t:?}");
    // Around the axis, inside the core; normals point outwards, to larger λ2.
    for (&v, &n) in one.mesh.vertices.iter().zip(&one.mesh.normals) {
        let d = Vec3::new(v.x - 0.5, v.y - 0.5, 0.0);
        assert!(d.length() < 1.12 * CORE, "vertex {v}");
        if d.length() > 0.5 * CORE && (v.z - 0.5).abs() < 0.1 {
            assert!(n.dot(d.normalize()) > 0.9, "normal {n} at {v}");
        }
    }
    assert!(
        one.mesh.triangles.len() > 500,
        "{}",
        one.mesh.triangles.len()
    );
}
