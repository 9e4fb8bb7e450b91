//! Every kind of scalar field on shapes with known answers, and every preset in configs/.

use crate::Engine;
use crate::config::{Config, Normals, Params};
use crate::field::FieldConfig;
use crate::length::Length;
use crate::mesh::TriMesh;
use crate::mesh::topology::{component_volumes, normal_agreement, topology};
use crate::tests::common::reconstruct;
use crate::tests::common::{field_params, fixture, lattice_ball, repository};
use glam::Vec3;

const R: f32 = 0.01;

fn params(kind: &str, cell: &str) -> Params {
    field_params(kind, R, cell)
}

/// Smallest and largest distance of the mesh's vertices from `centre`, in units of r.
fn radii(mesh: &TriMesh, centre: Vec3) -> (f32, f32) {
    mesh.vertices
        .iter()
        .map(|v| (*v - centre).length() / R)
        .fold((f32::MAX, 0.0), |(lo, hi), d| (lo.min(d), hi.max(d)))
}

#[test]
fn every_field_wraps_a_lattice_ball_in_one_closed_outward_sphere() {
    let centre = Vec3::new(0.1, 0.2, -0.3);
    let ball = lattice_ball(centre, 6.0 * R, R);
    // Where each field puts the surface of a ball whose outer particle centres lie at 6r
    // (measured, then widened by about r/4 each way for the cell's linear interpolation):
    // SSP07 and ZB05 just inside the outer centres, as x̄ lags inward; the colour field at 0.6
    // about the outer centres, pushed out by the outer particles' larger volumes m/ρ; blobbies and Triquet metaballs (lone-particle
    // radii 0.75r and r/2) outside them, reaching farther where the lattice's corners stick out.
    let expected = [
        ("ssp07", 5.3, 6.15),
        ("zb05", 5.3, 6.15),
        ("density", 5.4, 6.6),
        ("blobby", 5.7, 7.15),
        ("metaball", 5.7, 6.85),
        // Measured 5.59r to 6.14r: Yu–Turk kernels about the outer centres, which the smoothing
        // (λ = 0.3) pulls in by up to 0.3r, while the surface particles' kernels, flattened to
        // a quarter across the surface, reach out less than the density field's round ones.
        ("anisotropic", 5.3, 6.4),
    ];
    assert_eq!(expected.len(), FieldConfig::KINDS.len());
    for (kind, lo, hi) in expected {
        for cell in ["r", "r/2"] {
            let rec = reconstruct(&ball, &params(kind, cell), Engine::NarrowBand).unwrap();
            let what = format!("{kind} at cell {cell}");
            let t = topology(&rec.mesh);
            assert!(t.is_closed_manifold() && t.components == 1, "{what}: {t:?}");
            assert!(component_volumes(&rec.mesh)[0].1 > 0.0, "{what}: inward");
            assert!(normal_agreement(&rec.mesh) > 0.999, "{what}: normals");
            let (min, max) = radii(&rec.mesh, centre);
            assert!(
                min > lo && max < hi,
                "{what}: radii {min}r to {max}r, expected within {lo}r to {hi}r"
            );
        }
    }
}

#[test]
fn ssp07_keeps_the_neck_between_touching_balls_that_zb05_fills() {
    // Two balls of radius 5r touching at x = 5r: a concave neck, where ZB05's mean position x̄
    // moves faster than x and the surface bulges away from the particles (Akinci Sec. 3).
    let mut two = lattice_ball(Vec3::ZERO, 5.0 * R, R);
    two.extend(lattice_ball(Vec3::new(10.0 * R, 0.0, 0.0), 5.0 * R, R));
    let measure = |kind: &str| {
        let mesh = reconstruct(&two, &params(kind, "r/2"), Engine::NarrowBand)
            .unwrap()
            .mesh;
        assert!(topology(&mesh).is_closed_manifold(), "{kind}");
        let neck = mesh
            .vertices
            .iter()
            .filter(|v| (v.x - 5.0 * R).abs() < 0.3 * R)
            .map(|v| Vec3::new(0.0, v.y, v.z).length() / R)
            .fold(0.0, f32::max);
        let farthest = mesh
            .vertices
            .iter()
            .map(|v| {
                two.iter()
                    .map(|p| (*v - *p).length())
                    .fold(f32::MAX, f32::min)
                    / R
            })
            .fold(0.0, f32::max);
        (neck, farthest)
    };
    let (ssp07_neck, ssp07_far) = measure("ssp07");
    let (zb05_neck, zb05_far) = measure("zb05");
    // Measured: necks 3.08r and 3.40r, farthest vertices 1.34r and 1.50r from any particle.
    assert!(
        zb05_neck > ssp07_neck + 0.2,
        "necks: ZB05 {zb05_neck}r, SSP07 {ssp07_neck}r"
    );
    assert!(
        zb05_far > ssp07_far + 0.1,
        "farthest: ZB05 {zb05_far}r, SSP07 {ssp07_far}r"
    );
}

#[test]
fn every_preset_loads_and_reconstructs_a_real_frame() {
    let dir = repository().join("configs");
    let particles = crate::io::read_particles(&fixture("frame_0010.ply"), None)
        .unwrap()
        .positions;
    let mut presets = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        let mut config = Config::from_file(&path).unwrap();
        // At most cell r here, to keep the test quick; the presets' cells are checked above.
        config.cell = Length::Spacings(1.0);
        let p = Params::resolve(&config, config.spacing.unwrap_or(0.014));
        let mesh = reconstruct(&particles, &p, Engine::NarrowBand)
            .unwrap()
            .mesh;
        let t = topology(&mesh);
        assert!(
            t.triangles > 1000 && t.is_closed_manifold(),
            "{}: {t:?}",
            path.display()
        );
        presets += 1;
    }
    assert!(presets >= 6, "only {presets} presets in configs/");
}

/// Largest angle, in degrees, between a vertex normal and the direction from the nearest of
/// `centres`.
fn worst_radial_error(mesh: &TriMesh, centres: &[Vec3]) -> f32 {
    mesh.vertices
        .iter()
        .zip(&mesh.normals)
        .map(|(&v, n)| {
            let c = centres
                .iter()
                .min_by(|a, b| a.distance(v).total_cmp(&b.distance(v)))
                .unwrap();
            n.angle_between(v - *c).to_degrees()
        })
        .fold(0.0, f32::max)
}

#[test]
fn field_normals_of_lone_particles_are_radial() {
    // Splash particles far apart: every field makes each one an exact sphere, whose normals
    // are radial. Grid differences miss that by degrees: the field bends within a cell.
    let centres = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(0.113, 0.021, -0.017),
        Vec3::new(-0.05, 0.131, 0.071),
    ];
    for kind in FieldConfig::KINDS {
        for cell in ["r", "r/2"] {
            let mut p = params(kind, cell);
            let field = reconstruct(&centres, &p, Engine::NarrowBand).unwrap().mesh;
            p.normals = Normals::Grid;
            let grid = reconstruct(&centres, &p, Engine::NarrowBand).unwrap().mesh;
            p.normals = Normals::None;
            let none = reconstruct(&centres, &p, Engine::NarrowBand).unwrap().mesh;
            assert_eq!(field.vertices, grid.vertices);
            assert!(none.normals.is_empty() && none.vertices == field.vertices);
            let (f, g) = (
                worst_radial_error(&field, &centres),
                worst_radial_error(&grid, &centres),
            );
            // Measured: field ≤ 0.034° (f32 rounding), grid 2.3° to 25°.
            assert!(
                f < 0.1,
                "{kind} at cell {cell}: field normals {f}° off radial"
            );
            assert!(
                g > 1.0,
                "{kind} at cell {cell}: grid normals {g}°, test too easy"
            );
        }
    }
}
