//! The narrow-band reconstructor against shapes with known answers, against the full grid, and
//! on real frames.

use crate::Engine;
use crate::mesh::TriMesh;
use crate::mesh::topology::{component_volumes, normal_agreement, signed_volume, topology};
use crate::tests::common::reconstruct;
use crate::tests::common::{fixture, lattice_ball, params, shared_data};
use glam::Vec3;

const R: f32 = 0.01;

/// Closed, edge-manifold, and wound so that faces look along the field gradient, i.e. out of
/// the fluid. (A bubble inside the fluid is a component of negative volume, correctly: its
/// faces look into the bubble.) `agreement` is the share of vertices whose normal from the
/// field agrees with the winding; the coarse 2r grid resolves thin sheets poorly and earns a
/// lower bar.
fn assert_closed_outward(mesh: &TriMesh, what: &str, agreement: f64) {
    let t = topology(mesh);
    assert!(t.triangles > 0, "{what}: empty mesh");
    assert!(t.is_closed_manifold(), "{what}: {t:?}");
    assert_eq!(t.degenerate_triangles, 0, "{what}: {t:?}");
    assert!(
        signed_volume(mesh) > 0.0,
        "{what}: encloses negative volume"
    );
    let a = normal_agreement(mesh);
    assert!(
        a > agreement,
        "{what}: only {a} of the normals agree with the winding"
    );
}

fn agreement_at(cell: &str) -> f64 {
    if cell == "2r" { 0.95 } else { 0.99 }
}

#[test]
fn lattice_ball_gives_a_closed_outward_sphere_of_the_right_radius() {
    let radius = 8.0 * R;
    let ball = lattice_ball(Vec3::new(0.3, -0.2, 0.1), radius, R);
    for cell in ["2r", "r", "r/2"] {
        let rec = reconstruct(&ball, &params(R, cell), Engine::NarrowBand).unwrap();
        let what = format!("ball at cell {cell}");
        assert_closed_outward(&rec.mesh, &what, 0.999);
        assert_eq!(topology(&rec.mesh).components, 1, "{what}");
        // SSP07 puts the surface of a lattice ball just inside its outermost particle centres
        // (x̄ lags inward, so |x − x̄| = r̄ is met a little inside the last layer; measured
        // 7.49r–7.87r for radius 8r). Allow ±r/2 around radius − r/4, wide enough for the
        // lattice's corners and the cell's linear interpolation.
        let centre = Vec3::new(0.3, -0.2, 0.1);
        for v in &rec.mesh.vertices {
            let d = (*v - centre).length();
            assert!(
                (d - (radius - 0.25 * R)).abs() < 0.5 * R,
                "{what}: vertex at radius {d}"
            );
        }
    }
}

#[test]
fn two_separated_balls_give_two_outward_components() {
    let mut ps = lattice_ball(Vec3::ZERO, 5.0 * R, R);
    ps.extend(lattice_ball(Vec3::new(20.0 * R, 0.0, 0.0), 4.0 * R, R));
    let rec = reconstruct(&ps, &params(R, "r"), Engine::NarrowBand).unwrap();
    assert_closed_outward(&rec.mesh, "two balls", 0.999);
    assert!(component_volumes(&rec.mesh).iter().all(|c| c.1 > 0.0));
    assert_eq!(topology(&rec.mesh).components, 2);
}

/// Vertices by position and triangles as position triples, rotated to a canonical start, so
/// that meshes compare independently of vertex numbering.
fn canonical(mesh: &TriMesh) -> Vec<[[u32; 3]; 3]> {
    let key = |i: u32| mesh.vertices[i as usize].to_array().map(f32::to_bits);
    let mut tris: Vec<[[u32; 3]; 3]> = mesh
        .triangles
        .iter()
        .map(|t| {
            let k = t.map(key);
            let first = (0..3).min_by_key(|&i| k[i]).unwrap();
            [k[first], k[(first + 1) % 3], k[(first + 2) % 3]]
        })
        .collect();
    tris.sort();
    tris
}

#[test]
fn narrow_band_equals_the_full_grid() {
    let mut ps = lattice_ball(Vec3::ZERO, 6.0 * R, R);
    // A splash: two lone particles and a small cluster off the ball.
    ps.push(Vec3::new(9.5 * R, 0.0, 0.0));
    ps.push(Vec3::new(12.0 * R, 1.0 * R, 0.0));
    ps.extend(lattice_ball(Vec3::new(0.0, 11.0 * R, 0.0), 1.5 * R, R));
    for cell in ["r", "r/2"] {
        let p = params(R, cell);
        let band = reconstruct(&ps, &p, Engine::NarrowBand).unwrap();
        let full = reconstruct(&ps, &p, Engine::FullGather).unwrap();
        assert!(full.stats.surface_vertices > 2 * band.stats.surface_vertices);
        assert_eq!(canonical(&band.mesh), canonical(&full.mesh), "cell {cell}");
    }
}

#[test]
fn one_thread_and_three_threads_give_the_same_mesh() {
    let path = fixture("frame_0040.ply");
    let ps = crate::io::read_particles(&path, None).unwrap().positions;
    let run = |threads| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            reconstruct(&ps, &params(0.014, "r"), Engine::NarrowBand)
                .unwrap()
                .mesh
        })
    };
    assert_eq!(run(1), run(3));
}

#[test]
fn a_far_away_particle_costs_no_memory() {
    let ball = lattice_ball(Vec3::ZERO, 8.0 * R, R);
    let mut with_far = ball.clone();
    with_far.push(Vec3::new(1.0e4 * R, 0.0, 0.0));
    let p = params(R, "r/2");
    let a = reconstruct(&ball, &p, Engine::NarrowBand).unwrap().stats;
    let b = reconstruct(&with_far, &p, Engine::NarrowBand)
        .unwrap()
        .stats;
    // The stray particle adds a tiny ball: a few bricks of 2 kB and its triangles.
    assert!(
        (b.peak_bytes as f64) < a.peak_bytes as f64 * 1.1 + 100e3,
        "{} bytes without, {} with the stray particle",
        a.peak_bytes,
        b.peak_bytes
    );
    assert_eq!(b.particles, a.particles + 1);
}

#[test]
fn real_frames_give_closed_outward_meshes() {
    let mut frames = vec![
        (fixture("frame_0010.ply"), 0.014),
        (fixture("frame_0040.ply"), 0.014),
    ];
    for name in ["cbd-small/frame_0022.ply", "cbd-small/frame_0061.ply"] {
        frames.extend(shared_data(name).map(|p| (p, 0.014)));
    }
    for (path, r) in frames {
        let ps = crate::io::read_particles(&path, None).unwrap().positions;
        for cell in ["2r", "r", "r/2"] {
            let rec = reconstruct(&ps, &params(r, cell), Engine::NarrowBand).unwrap();
            let what = format!("{} at cell {cell}", path.display());
            assert_closed_outward(&rec.mesh, &what, agreement_at(cell));
        }
    }
}

#[test]
fn large_real_frame_gives_a_closed_outward_mesh() {
    let Some(path) = shared_data("cbd-large/frame_0023.ply") else {
        return;
    };
    let ps = crate::io::read_particles(&path, None).unwrap().positions;
    let rec = reconstruct(&ps, &params(0.005, "r"), Engine::NarrowBand).unwrap();
    assert_closed_outward(&rec.mesh, "cbd-large frame 23 at cell r", agreement_at("r"));
}
