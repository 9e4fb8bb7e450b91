//! Post-processing (mesh::post) on analytic particle sets and a real frame: the particles'
//! volume, flat faces and corners kept, topology kept, the same bytes on 1 and 2 threads;
//! `postprocess_mesh` on meshes from elsewhere: the same bytes, volumes kept, bad meshes refused.

use glam::Vec3;

use crate::mesh::post::{PostConfig, Volumes, postprocess_mesh};
use crate::mesh::topology::{component_volumes, normal_agreement, signed_volume, topology};
use crate::mesh::{TriMesh, VolumeScope, self_intersecting_faces};
use crate::tests::common::{fixture, lattice_ball, shared_data, torus};
use crate::{Config, Length, Reconstructor};

const R: f32 = 0.1;

fn mesh(particles: &[Vec3], raw: bool, threads: usize) -> TriMesh {
    configured(
        particles,
        Some(threads),
        PostConfig {
            raw,
            ..PostConfig::default()
        },
    )
}

fn configured(particles: &[Vec3], threads: Option<usize>, post: PostConfig) -> TriMesh {
    at_spacing(particles, R, threads, post)
}

/// The mesh of `particles` at spacing `spacing`, cell r/2, post-processed by `post`.
pub(crate) fn at_spacing(
    particles: &[Vec3],
    spacing: f32,
    threads: Option<usize>,
    post: PostConfig,
) -> TriMesh {
    let config = Config {
        spacing: Some(spacing),
        threads,
        cell: Length::Spacings(0.5),
        post,
        ..Config::default()
    };
    Reconstructor::new(config)
        .unwrap()
        .reconstruct(particles)
        .unwrap()
        .mesh
}

/// Particles on the lattice of spacing R filling [0, n·R)³.
fn lattice_box(n: i32) -> Vec<Vec3> {
    let mut out = Vec::new();
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                out.push(Vec3::new(x as f32, y as f32, z as f32) * R);
            }
        }
    }
    out
}

fn volume_error(mesh: &TriMesh, particles: usize) -> f64 {
    signed_volume(mesh) / (particles as f64 * f64::from(R).powi(3)) - 1.0
}

/// Closed, manifold, outward, with the raw mesh's components and Euler characteristic, and its
/// triangles or more (the refinement only bisects).
fn assert_topology_kept(raw: &TriMesh, post: &TriMesh) {
    let (a, b) = (topology(raw), topology(post));
    assert!(b.is_closed_manifold(), "{b:?}");
    assert_eq!(
        (a.components, a.euler_characteristic),
        (b.components, b.euler_characteristic)
    );
    assert!(b.triangles >= a.triangles, "{a:?} {b:?}");
    assert!(normal_agreement(post) > 0.999, "{}", normal_agreement(post));
}

#[test]
fn a_ball_of_particles_gets_their_volume_and_keeps_its_topology() {
    let particles = lattice_ball(Vec3::splat(0.05), 8.0 * R, R);
    let (raw, post) = (mesh(&particles, true, 2), mesh(&particles, false, 2));
    let (before, after) = (
        volume_error(&raw, particles.len()),
        volume_error(&post, particles.len()),
    );
    assert!(after.abs() < 0.01, "raw {before:+.4}, post {after:+.4}");
    assert_topology_kept(&raw, &post);
}

#[test]
fn a_box_keeps_its_volume_its_flat_faces_and_its_corners() {
    let n = 12;
    let particles = lattice_box(n);
    let (raw, post) = (mesh(&particles, true, 2), mesh(&particles, false, 2));
    let error = volume_error(&post, particles.len());
    assert!(
        error.abs() < 0.01,
        "raw {:+.4}, post {error:+.4}",
        volume_error(&raw, particles.len())
    );
    assert_topology_kept(&raw, &post);

    // The top face's middle (a cell and more from every edge of the box's top): flat.
    let (lo, hi) = (2.0 * R, (n - 3) as f32 * R);
    let top_z = post.vertices.iter().map(|p| p.z).fold(f32::MIN, f32::max);
    let face: Vec<f32> = post
        .vertices
        .iter()
        .filter(|p| p.x > lo && p.x < hi && p.y > lo && p.y < hi && p.z > top_z - R)
        .map(|p| p.z)
        .collect();
    assert!(face.len() > 100, "{}", face.len());
    let spread =
        face.iter().fold(f32::MIN, |a, &b| a.max(b)) - face.iter().fold(f32::MAX, |a, &b| a.min(b));
    // Measured 0.0203 R with the default λ 0.6 and 9 rounds (0.02 R or less with λ 0.5 and 6):
    // the rounding of the box's edges reaches two spacings in by a fiftieth of a spacing.
    assert!(spread < 0.03 * R, "top face spread {spread}");

    // Corners: the post mesh comes as close to each corner of the raw mesh's bounding box as
    // the raw mesh does, give or take a cell.
    let bound = |m: &TriMesh| {
        m.vertices
            .iter()
            .fold((Vec3::MAX, Vec3::MIN), |(a, b), &p| (a.min(p), b.max(p)))
    };
    let (a, b) = bound(&raw);
    for k in 0..8 {
        let corner = Vec3::new(
            if k & 1 == 0 { a.x } else { b.x },
            if k & 2 == 0 { a.y } else { b.y },
            if k & 4 == 0 { a.z } else { b.z },
        );
        let nearest = |m: &TriMesh| {
            m.vertices
                .iter()
                .map(|p| p.distance(corner))
                .fold(f32::MAX, f32::min)
        };
        let (d_raw, d_post) = (nearest(&raw), nearest(&post));
        assert!(
            d_post < d_raw + 0.5 * R,
            "corner {k}: raw {d_raw}, post {d_post}"
        );
    }
}

/// A ball and, apart, two lone particles and a pair, whose components' volumes (in r³,
/// smallest first) post-processing with `scope` gives, beside those of the raw mesh and the
/// ball's particle count.
fn droplets(scope: VolumeScope) -> (Vec<f64>, Vec<f64>, usize) {
    let mut particles = lattice_ball(Vec3::ZERO, 5.0 * R, R);
    let ball = particles.len();
    particles.extend([
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(R, 0.0, 1.0),
    ]);
    let volumes = |raw| {
        let post = PostConfig {
            raw,
            volume_scope: scope,
            ..PostConfig::default()
        };
        let mut v: Vec<f64> = component_volumes(&configured(&particles, Some(2), post))
            .iter()
            .map(|v| v.1 / f64::from(R).powi(3))
            .collect();
        v.sort_by(f64::total_cmp);
        v
    };
    (volumes(false), volumes(true), ball)
}

#[test]
fn droplets_get_the_volume_of_their_particles_each() {
    // The field swells the droplets to spheres (3.6 r³ a lone particle's at r/2); post-processing
    // by component brings the pair and the ball to their particles' volume, and the lone
    // particles as far as their clearance lets them shrink (their focal distance, less the
    // margin): to about 2 r³.
    let (got, raw, ball) = droplets(VolumeScope::Component);
    assert_eq!(got.len(), 4, "{got:?}");
    for (g, r) in got.iter().zip(&raw).take(2) {
        assert!(*g > 1.0 && *g < 0.6 * r, "{got:?} from {raw:?}");
    }
    // The pair holds its two particles' volume (the lone ones may end near it too).
    let pair = got.iter().find(|g| (**g / 2.0 - 1.0).abs() < 0.01);
    assert!(pair.is_some(), "{got:?}");
    assert!((got[3] / ball as f64 - 1.0).abs() < 0.01, "{got:?}");
}

#[test]
fn one_offset_brings_the_frame_to_its_particles_volume() {
    // By frame, the whole mesh holds its particles' volume, and every droplet moves with the
    // ball's offset: the raw lattice ball holds less than its particles' volume, so the ball
    // and the droplets grow (a lone particle from its raw sphere's 4.2 r³ to 6.4 r³), the lone
    // two alike, the pair more.
    let (got, raw, ball) = droplets(VolumeScope::Frame);
    assert_eq!(got.len(), 4, "{got:?}");
    let total: f64 = got.iter().sum();
    assert!((total / (ball + 4) as f64 - 1.0).abs() < 0.01, "{got:?}");
    assert!(raw[3] < ball as f64, "{raw:?}");
    assert!((got[0] - got[1]).abs() < 0.02 * got[0], "{got:?}");
    for (g, r) in got.iter().zip(&raw) {
        assert!(*g > 1.1 * r, "{got:?} from {raw:?}");
    }
    assert!(got[2] > got[1], "{got:?}");
}

#[test]
fn post_processing_gives_the_same_bytes_on_one_and_two_threads() {
    let mut particles = lattice_ball(Vec3::ZERO, 6.0 * R, R);
    particles.extend(lattice_ball(Vec3::new(1.5, 0.2, 0.0), 2.0 * R, R));
    let (one, two) = (mesh(&particles, false, 1), mesh(&particles, false, 2));
    assert_eq!(one, two);
    assert_ne!(one, mesh(&particles, true, 2));
}

#[test]
fn a_real_splashing_frame_stays_closed_manifold_and_outward() {
    let Some(path) = shared_data("cbd-small/frame_0040.ply") else {
        return;
    };
    let particles = crate::read_particles(&path, None).unwrap().positions;
    let run = |raw| {
        let post = PostConfig {
            raw,
            ..PostConfig::default()
        };
        at_spacing(&particles, 0.014, Some(2), post)
    };
    let (raw, post) = (run(true), run(false));
    assert_topology_kept(&raw, &post);
    let error = signed_volume(&post) / (particles.len() as f64 * 0.014f64.powi(3)) - 1.0;
    assert!(error.abs() < 0.02, "{error}");
}

#[test]
fn real_frames_whose_sheets_the_volume_steps_crossed_no_longer_cross() {
    // cbd-small frames 31, 34 and 37: before the clearance, the default post-processing (by
    // frame, without refinement) crossed 27, 118 and 113 faces of them; raw, none.
    for frame in [31, 34, 37] {
        let Some(path) = shared_data(&format!("cbd-small/frame_{frame:04}.ply")) else {
            return;
        };
        let particles = crate::read_particles(&path, None).unwrap().positions;
        let mesh = at_spacing(&particles, 0.014, Some(2), PostConfig::default());
        let crossing = self_intersecting_faces(&mesh.vertices, &mesh.triangles);
        assert!(
            crossing.is_empty(),
            "frame {frame}: {} faces cross",
            crossing.len()
        );
        assert!(topology(&mesh).is_closed_manifold());
    }
}

#[test]
fn faces_the_smoothing_makes_cross_go_back_to_the_raw_surface() {
    // The bundled frame at cell 2r (SSP07) and at r (density): before the guard against
    // crossings the default crossed 10 and 4 faces, sheets smoothed into each other (at 2r
    // Marching Cubes' own surface crosses 8, which the smoothing takes apart).
    let particles = crate::read_particles(&fixture("frame_0040.ply"), None)
        .unwrap()
        .positions;
    for (cell, field) in [(2.0, "ssp07"), (1.0, "density")] {
        let run = |raw| {
            let config = Config {
                field: crate::field::FieldConfig::named(field).unwrap(),
                spacing: Some(0.014),
                cell: Length::Spacings(cell),
                post: PostConfig {
                    raw,
                    ..PostConfig::default()
                },
                ..Config::default()
            };
            Reconstructor::new(config)
                .unwrap()
                .reconstruct(&particles)
                .unwrap()
                .mesh
        };
        let (raw, post) = (run(true), run(false));
        let crossing = self_intersecting_faces(&post.vertices, &post.triangles);
        assert!(
            crossing.is_empty(),
            "cell {cell} r: {} faces cross",
            crossing.len()
        );
        assert_topology_kept(&raw, &post);
    }
}

#[test]
fn min_component_drops_a_lone_particle_and_keeps_a_ball_of_fifty() {
    // A ball of 50 particles (the lattice points nearest its centre) and one particle 2 m away.
    let mut ball = lattice_box(6);
    let centre = Vec3::splat(2.5 * R);
    ball.sort_by(|a, b| a.distance(centre).total_cmp(&b.distance(centre)));
    ball.truncate(50);
    let mut particles = ball.clone();
    particles.push(Vec3::new(2.0, 0.0, 0.0));
    // By component, so that the lone particle holds r³ and the ball its 50 (by frame, the
    // lone one keeps some of its swelling, and the ball lends it that volume).
    let post = PostConfig {
        volume_scope: VolumeScope::Component,
        ..PostConfig::default()
    };
    let kept = configured(&particles, None, post.clone());
    assert_eq!(topology(&kept).components, 2);
    let dropped = configured(
        &particles,
        None,
        PostConfig {
            min_component: Some(2.0),
            ..post
        },
    );
    let t = topology(&dropped);
    assert_eq!(t.components, 1, "{t:?}");
    assert!(t.is_closed_manifold());
    assert!(dropped.vertices.iter().all(|v| v.x < 1.0));
    // The ball that stays holds its 50 particles' volume.
    assert!(
        volume_error(&dropped, 50).abs() < 0.02,
        "{}",
        volume_error(&dropped, 50)
    );
}

#[test]
fn a_mesh_box_and_decimation_asked_in_the_configuration_keep_the_mesh_closed() {
    let particles = lattice_box(12);
    let full = configured(&particles, None, PostConfig::default());
    // Cut the box of particles in half along x: the cap is flat at x = 0.55.
    let cut = 5.5 * R;
    let clipped = configured(
        &particles,
        None,
        PostConfig {
            mesh_aabb: Some([-10.0, -10.0, -10.0, cut, 10.0, 10.0]),
            ..PostConfig::default()
        },
    );
    let t = topology(&clipped);
    assert!(t.is_closed_manifold(), "{t:?}");
    assert!(clipped.vertices.iter().all(|v| v.x <= cut + 1e-4));
    let ratio = signed_volume(&clipped) / signed_volume(&full);
    assert!((0.45..0.55).contains(&ratio), "{ratio}");

    let decimated = configured(
        &particles,
        None,
        PostConfig {
            decimate: Some(Length::Spacings(0.1)),
            ..PostConfig::default()
        },
    );
    let t = topology(&decimated);
    assert!(t.is_closed_manifold(), "{t:?}");
    assert!(decimated.triangles.len() * 2 < full.triangles.len());
    assert_eq!(decimated.normals.len(), decimated.vertices.len());
    let change = signed_volume(&decimated) / signed_volume(&full) - 1.0;
    assert!(change.abs() < 0.01, "{change}");
}

#[test]
fn postprocess_mesh_on_the_raw_mesh_gives_the_reconstructors_bytes() {
    let mut particles = lattice_ball(Vec3::ZERO, 6.0 * R, R);
    particles.extend(lattice_ball(Vec3::new(1.5, 0.2, 0.0), 2.0 * R, R));
    let mut raw = mesh(&particles, true, 2);
    let volumes = Volumes::Particles {
        particles: &particles,
        cell: 0.5 * R,
    };
    postprocess_mesh(&mut raw, R, volumes, &PostConfig::default(), true).unwrap();
    assert_eq!(raw, mesh(&particles, false, 2));
}

#[test]
fn postprocess_mesh_without_particles_keeps_each_components_volume() {
    // A ball and a torus (genus 1), apart, each keeping its own volume while smoothing
    // moves every vertex.
    let mut input = mesh(&lattice_ball(Vec3::ZERO, 5.0 * R, R), true, 2);
    let ring = torus(48, 24, 1.0, 0.3, 0.5);
    let offset = input.vertices.len() as u32;
    input
        .vertices
        .extend(ring.vertices.iter().map(|v| *v + Vec3::new(3.0, 0.0, 0.0)));
    input.normals.clear();
    input
        .triangles
        .extend(ring.triangles.iter().map(|t| t.map(|i| i + offset)));
    let mut post = input.clone();
    postprocess_mesh(&mut post, R, Volumes::Kept, &PostConfig::default(), true).unwrap();
    assert_topology_kept(&input, &post);
    let (before, after) = (component_volumes(&input), component_volumes(&post));
    for (b, a) in before.iter().zip(&after) {
        assert!((a.1 / b.1 - 1.0).abs() < 1e-3, "{before:?} -> {after:?}");
    }
    assert!(
        input
            .vertices
            .iter()
            .zip(&post.vertices)
            .any(|(a, b)| a.distance(*b) > 1e-3 * R),
        "smoothing moved nothing"
    );
}

#[test]
fn postprocess_mesh_refuses_open_and_broken_meshes_naming_what_is_wrong() {
    let closed = mesh(&lattice_ball(Vec3::ZERO, 3.0 * R, R), true, 2);
    let config = PostConfig::default();
    let run = |mut m: TriMesh| {
        postprocess_mesh(&mut m, R, Volumes::Kept, &config, true)
            .unwrap_err()
            .to_string()
    };
    let mut open = closed.clone();
    open.triangles.pop();
    assert!(run(open).contains("3 boundary edges"));
    let mut doubled = closed.clone();
    doubled.triangles.push(closed.triangles[0]);
    assert!(run(doubled).contains("3 non-manifold edges"));
    let mut flipped = closed.clone();
    flipped.triangles[0].swap(0, 1);
    assert!(run(flipped).contains("3 edges whose two triangles wind the same way"));
    let mut missing = closed.clone();
    missing.triangles[5][1] = closed.vertices.len() as u32;
    assert!(run(missing).contains("triangle 5 references vertex"));
    let mut infinite = closed.clone();
    infinite.vertices[7].y = f32::NAN;
    assert!(run(infinite).contains("vertex 7 is not finite"));
    let mut m = closed.clone();
    let err = postprocess_mesh(&mut m, 0.0, Volumes::Kept, &config, true).unwrap_err();
    assert!(matches!(err, crate::Error::Config(_)), "{err}");
    let bad = [Vec3::new(0.0, f32::INFINITY, 0.0)];
    let volumes = Volumes::Particles {
        particles: &bad,
        cell: R,
    };
    let err = postprocess_mesh(&mut m, R, volumes, &config, true).unwrap_err();
    assert!(err.to_string().contains("particle 0"), "{err}");
}

#[test]
fn refining_where_the_surface_bends_keeps_volume_and_topology_and_smooths_droplets() {
    // A ball and lone droplets: the droplets' rims bend far more than the ball's face.
    let mut particles = lattice_ball(Vec3::ZERO, 5.0 * R, R);
    let n = particles.len();
    particles.extend([Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)]);
    let refined_config = |angle| PostConfig {
        refine_angle: angle,
        ..PostConfig::default()
    };
    let plain = configured(&particles, Some(2), refined_config(0.0));
    let refined = configured(&particles, Some(2), refined_config(16.0));
    let (a, b) = (topology(&plain), topology(&refined));
    assert!(b.is_closed_manifold(), "{b:?}");
    assert_eq!(
        (a.components, a.euler_characteristic),
        (b.components, b.euler_characteristic)
    );
    assert!(
        b.triangles > a.triangles,
        "{} -> {}",
        a.triangles,
        b.triangles
    );
    assert!(normal_agreement(&refined) > 0.999);
    let error = volume_error(&refined, particles.len());
    assert!(
        error.abs() < 0.01,
        "volume error {error:+.4} ({n} + 2 particles)"
    );
    let (before, after) = (
        crate::mesh::quality::bumpiness(&plain),
        crate::mesh::quality::bumpiness(&refined),
    );
    // Measured 4.28° -> 3.97°: the ball's face bends less than 16° and keeps its triangles.
    assert!(
        after < 0.95 * before,
        "bumpiness {before:.2}° -> {after:.2}°"
    );
    assert_eq!(
        refined,
        configured(&particles, Some(1), refined_config(16.0)),
        "1 vs 2 threads"
    );
}
