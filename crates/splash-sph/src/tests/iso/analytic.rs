//! `splash iso` on analytic fields: a linear attribute gives a plane, a distance a sphere; the
//! corrected vertices satisfy the SPH interpolant (evaluated here by brute force) to 1e-5.

use std::collections::BTreeMap;

use glam::{DVec3, Vec3};

use crate::config::Config;
use crate::io::Attribute;
use crate::iso::{Derived, IsoRequest, Isosurface, extract};
use crate::length::Length;
use crate::mesh::topology::topology;

const R: f32 = 0.05;

/// Particles on a lattice of spacing R filling [0, 1]³, each of volume R³ (mass R³, density 1),
/// carrying `a(x)`.
fn lattice_box(a: impl Fn(Vec3) -> f32) -> (Vec<Vec3>, BTreeMap<String, Attribute>) {
    let n = (1.0 / R).round() as i32;
    let positions: Vec<Vec3> = (0..=n)
        .flat_map(|z| (0..=n).flat_map(move |y| (0..=n).map(move |x| (x, y, z))))
        .map(|(x, y, z)| Vec3::new(x as f32, y as f32, z as f32) * R)
        .collect();
    let mut attributes = BTreeMap::new();
    let count = positions.len();
    attributes.insert(
        "a".into(),
        Attribute::Scalar(positions.iter().map(|&p| a(p)).collect()),
    );
    attributes.insert("mass".into(), Attribute::Scalar(vec![R * R * R; count]));
    attributes.insert("density".into(), Attribute::Scalar(vec![1.0; count]));
    (positions, attributes)
}

fn config(correct: u32, shepard: bool) -> Config {
    let mut c = Config {
        spacing: Some(R),
        cell: Length::Spacings(0.5),
        ..Config::default()
    };
    c.iso.correct = correct;
    c.iso.shepard = shepard;
    c
}

fn iso(
    positions: &[Vec3],
    attributes: &BTreeMap<String, Attribute>,
    level: f32,
    config: &Config,
) -> Isosurface {
    let request = IsoRequest {
        attribute: "a".into(),
        derived: Derived::Value,
        level,
    };
    extract(positions, attributes.clone(), &request, config).unwrap()
}

/// Σ_j V_j A_j W(x − x_j) over every particle (divided by Σ_j V_j W with `shepard`), in f64,
/// with the cubic spline of support 2R.
fn brute_force(positions: &[Vec3], a: &[f32], x: Vec3, shepard: bool) -> f64 {
    let s = 2.0 * f64::from(R);
    let volume = f64::from(R * R * R);
    let (n, d) = positions
        .iter()
        .zip(a)
        .map(|(&p, &a)| {
            let q = (x.as_dvec3() - p.as_dvec3()).length() / s;
            let w = if q <= 0.5 {
                6.0 * q * q * q - 6.0 * q * q + 1.0
            } else if q <= 1.0 {
                2.0 * (1.0 - q).powi(3)
            } else {
                0.0
            };
            let vw = volume * w * 8.0 / (std::f64::consts::PI * s * s * s);
            (vw * f64::from(a), vw)
        })
        .fold((0.0, 0.0), |(n, d), (a, w)| (n + a, d + w));
    if shepard { n / d } else { n }
}

fn values(attributes: &BTreeMap<String, Attribute>) -> &[f32] {
    match &attributes["a"] {
        Attribute::Scalar(s) => s,
        Attribute::Vector(_) => unreachable!(),
    }
}

#[test]
fn a_linear_attribute_gives_the_plane_trimmed_at_the_boundary_and_corrected_to_1e5() {
    let (positions, attributes) = lattice_box(|p| p.x);
    let c = 0.537f32;
    let a = values(&attributes);
    let residual = |surface: &Isosurface| {
        surface
            .mesh
            .vertices
            .iter()
            .map(|&v| (brute_force(&positions, a, v, true) - f64::from(c)).abs())
            .fold(0.0f64, f64::max)
    };
    // Shepard normalisation: plain SPH's Σ V A W falls with the weights at the walls, and its
    // level set bends along them where x·Σ V W = c (a real feature of that interpolant).
    let corrected = iso(&positions, &attributes, c, &config(3, true));
    let linear = iso(&positions, &attributes, c, &config(0, true));
    let (rc, rl) = (residual(&corrected), residual(&linear));
    eprintln!("{}", corrected.stats);
    assert!(rc <= 1e-5 * f64::from(c), "corrected residual {rc}");
    assert!(
        rl > 1e-5 * f64::from(c) && rl > 10.0 * rc,
        "linear {rl}, corrected {rc}"
    );
    let mesh = &corrected.mesh;
    assert!(mesh.triangles.len() > 500, "{}", mesh.triangles.len());
    // The plane x = c inside the fluid: away from the walls the Shepard interpolant of x is x
    // up to the lattice's discretisation of the kernel sums (measured: 0.0033 R).
    for (&v, &n) in mesh.vertices.iter().zip(&mesh.normals) {
        assert!((v.x - c).abs() < 0.2 * R, "vertex {v}");
        let inner = (0.15..0.85).contains(&v.y) && (0.15..0.85).contains(&v.z);
        if inner {
            assert!(
                (v.x - c).abs() < 0.01 * R && n.dot(Vec3::X) > 0.999,
                "{v} {n}"
            );
        }
    }
    // Trimmed where the sum of weights falls below ½: an open sheet with one boundary loop,
    // consistently wound, manifold.
    let t = topology(mesh);
    assert!(t.boundary_edges > 0, "{t:?}");
    assert_eq!(
        (t.non_manifold_edges, t.inconsistent_edges, t.components),
        (0, 0, 1),
        "{t:?}"
    );
    assert_eq!(t.euler_characteristic, 1, "a disc: {t:?}");
    let s = corrected.stats;
    assert!(
        s.trim_cases[0] > 0 && s.trim_cases[1] + s.trim_cases[2] + s.trim_cases[3] > 0,
        "{s}"
    );
    // The sheet reaches the particles' box nearly to the walls, not beyond them.
    let (lo, hi) = mesh
        .vertices
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), &v| {
            (l.min(v), h.max(v))
        });
    assert!(
        lo.y > -R && lo.y < 0.1 && hi.y < 1.0 + R && hi.y > 0.9,
        "{lo} {hi}"
    );
}

#[test]
fn a_distance_gives_a_closed_sphere_of_the_right_radius() {
    let centre = Vec3::splat(0.5);
    let (positions, attributes) = lattice_box(|p| (p - centre).length());
    let radius = 0.3;
    let surface = iso(&positions, &attributes, radius, &config(3, false));
    let t = topology(&surface.mesh);
    assert!(t.is_closed_manifold(), "{t:?}");
    assert_eq!((t.components, t.euler_characteristic), (1, 2), "{t:?}");
    let a = values(&attributes);
    for (&v, &n) in surface.mesh.vertices.iter().zip(&surface.mesh.normals) {
        let d = v - centre;
        assert!((d.length() - radius).abs() < 0.1 * R, "{v}: {}", d.length());
        assert!(n.dot(d.normalize()) > 0.99, "normal {n} at {v}");
        let residual = (brute_force(&positions, a, v, false) - f64::from(radius)).abs();
        assert!(residual <= 1e-5 * f64::from(radius), "{residual}");
    }
    // Enclosed volume ≈ 4/3 π r³, the triangles wound outwards (towards larger A); smoothing
    // the convex |x − c| raises it, so the SPH sphere is a little smaller (measured: −2.8 %).
    let volume: f64 = surface
        .mesh
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] =
                t.map(|i| surface.mesh.vertices[i as usize].as_dvec3() - DVec3::splat(0.5));
            a.dot(b.cross(c)) / 6.0
        })
        .sum();
    let exact = 4.0 / 3.0 * std::f64::consts::PI * f64::from(radius).powi(3);
    assert!((volume / exact - 1.0).abs() < 0.04, "{volume} vs {exact}");
    assert_eq!(
        surface.stats.trim_cases[1..],
        [0, 0, 0, 0],
        "nothing trimmed inside the fluid"
    );
}

#[test]
fn the_mesh_does_not_depend_on_the_thread_count() {
    let centre = Vec3::new(0.4, 0.55, 0.5);
    let (positions, attributes) = lattice_box(|p| (p - centre).length() + 0.2 * p.x * p.y);
    let mut one = config(3, false);
    one.threads = Some(1);
    let mut two = config(3, false);
    two.threads = Some(2);
    let a = iso(&positions, &attributes, 0.45, &one);
    let b = iso(&positions, &attributes, 0.45, &two);
    assert!(a.mesh.triangles.len() > 1000);
    assert_eq!(a.mesh, b.mesh);
}

#[test]
fn unknown_attributes_and_vectors_without_magnitude_are_clear_errors() {
    let (positions, mut attributes) = lattice_box(|p| p.x);
    let n = positions.len();
    attributes.insert("velocity".into(), Attribute::Vector(vec![Vec3::X; n]));
    let ask = |name: &str, derived| IsoRequest {
        attribute: name.into(),
        derived,
        level: 0.5,
    };
    let e = extract(
        &positions,
        attributes.clone(),
        &ask("pressure", Derived::Value),
        &config(3, false),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("'pressure'") && e.contains("a, density, mass, velocity"),
        "{e}"
    );
    let e = extract(
        &positions,
        attributes.clone(),
        &ask("vel", Derived::Value),
        &config(3, false),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("vector") && e.contains("--magnitude"), "{e}");
    let e = extract(
        &positions,
        attributes.clone(),
        &ask("a", Derived::Magnitude),
        &config(3, false),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("scalar"), "{e}");
    // |v| = 1 everywhere: the magnitude works, the level 0.5 crosses nowhere inside.
    let s = extract(
        &positions,
        attributes,
        &ask("v", Derived::Magnitude),
        &config(3, false),
    )
    .unwrap();
    assert_eq!(s.stats.seed_cells, 0);
}
