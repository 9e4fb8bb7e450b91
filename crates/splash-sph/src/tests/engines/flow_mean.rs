//! The field averaged along the flow (`recon/stages/flow_mean`): a fluid that moves as a
//! whole keeps its own surface; particles that rearrange from frame to frame get a surface
//! nearer the one their frames share; the mesh does not depend on the thread count.

use glam::Vec3;

use crate::config::Config;
use crate::length::Length;
use crate::mesh::SignedDistance;
use crate::recon::{Sampled, Sides};
use crate::tests::common::{lattice_ball, uniform, uniform_point};
use crate::{Reconstructor, TriMesh};

const R: f32 = 0.05;

/// The raw surface of `field` at cell r/2 on `threads` threads (all when None).
fn reconstructor(field: &str, threads: Option<usize>) -> Reconstructor {
    let mut config = Config {
        spacing: Some(R),
        cell: Length::parse("r/2").unwrap(),
        threads,
        field: crate::field::FieldConfig::named(field).unwrap(),
        ..Config::default()
    };
    config.post.raw = true;
    Reconstructor::new(config).unwrap()
}

/// `particles`' field sampled on its closed band, as a sequence samples each frame's.
fn sampled(rec: &Reconstructor, particles: &[Vec3]) -> Sampled {
    rec.sample(particles, None)
        .unwrap()
        .expect("the narrow band samples")
}

/// Frame t's raw surface with its field averaged with frames `before` and `after`, whose
/// particles are frame t's in the same order (matched by index).
fn along_flow(rec: &Reconstructor, own: &[Vec3], before: &[Vec3], after: &[Vec3]) -> TriMesh {
    let moves = |side: &[Vec3]| -> Vec<Option<Vec3>> {
        own.iter().zip(side).map(|(a, b)| Some(*b - *a)).collect()
    };
    let (back, ahead) = (moves(before), moves(after));
    let fields = [own, before, after].map(|p| sampled(rec, p));
    let sides = Sides {
        fields: [&fields[1], &fields[2]],
        moves: [&back, &ahead],
    };
    let out = rec
        .reconstruct_along_flow(own, Some(&fields[0]), Some(&sides), None)
        .unwrap();
    assert!(out.stats.flow_mean_vertices > 0);
    out.mesh
}

/// A ball stepping 0.37 cell a frame: the fields of the frames beside are frame t's own
/// carried with it, read between the grid's vertices by trilinear interpolation, which lies
/// above a convex field and so moves the surface in by a nearly even 0.007 r (SSP07, ZB05;
/// the density field, bumpier between vertices, up to 0.05 r): the surface stays frame t's
/// within that, with any field that averages.
#[test]
fn a_fluid_moving_as_a_whole_keeps_its_own_surface() {
    for (field, within) in [("ssp07", 0.01), ("zb05", 0.01), ("density", 0.05)] {
        let rec = reconstructor(field, None);
        let ball = lattice_ball(Vec3::splat(0.3), 5.0 * R, R);
        let step = Vec3::new(0.37, 0.11, -0.23) * 0.5 * R;
        let shifted = |k: f32| -> Vec<Vec3> { ball.iter().map(|p| *p + k * step).collect() };
        let own = rec.reconstruct(&ball).unwrap().mesh;
        let mean = along_flow(&rec, &ball, &shifted(-1.0), &shifted(1.0));
        assert!(own.triangles.len() > 1000);
        let surface = SignedDistance::new(&own.vertices, &own.triangles, 4.0 * R);
        for v in &mean.vertices {
            let d = surface.at(*v).unwrap() / R;
            assert!(
                d.abs() < within,
                "{field}: a vertex {d} r off frame t's own surface"
            );
        }
    }
}

/// A bump of frame t alone (a particle the frames beside it lack, on a ball that moves 0.37
/// cell a frame): the mean keeps under half of it (0.147 → 0.058 r with frame t weighing
/// 0.44), the ball carried exactly as the fluid moves.
#[test]
fn a_bump_of_one_frame_is_shared_with_the_frames_beside_it() {
    let rec = reconstructor("ssp07", None);
    let centre = Vec3::splat(0.3);
    let ball = lattice_ball(centre, 5.0 * R, R);
    let top = ball.iter().map(|p| p.x).fold(f32::MIN, f32::max);
    let mut frame = ball.clone();
    frame.push(Vec3::new(top + 1.2 * R, centre.y, centre.z));
    let step = Vec3::new(0.37, 0.11, -0.23) * 0.5 * R;
    let side = |k: f32| -> Vec<Vec3> { ball.iter().map(|p| *p + k * step).collect() };
    let (before, after) = (side(-1.0), side(1.0));
    let moves = |k: f32| -> Vec<Option<Vec3>> {
        (0..frame.len())
            .map(|i| (i < ball.len()).then_some(k * step))
            .collect()
    };
    let (back, ahead) = (moves(-1.0), moves(1.0));
    let fields = [&frame, &before, &after].map(|p| sampled(&rec, p));
    let sides = Sides {
        fields: [&fields[1], &fields[2]],
        moves: [&back, &ahead],
    };
    let own = rec.reconstruct(&frame).unwrap().mesh;
    let mean = rec
        .reconstruct_along_flow(&frame, Some(&fields[0]), Some(&sides), None)
        .unwrap()
        .mesh;
    let plain = rec.reconstruct(&ball).unwrap().mesh;
    let surface = SignedDistance::new(&plain.vertices, &plain.triangles, 4.0 * R);
    let bump = |m: &TriMesh| {
        m.vertices
            .iter()
            .map(|v| surface.at(*v).unwrap())
            .fold(0.0f32, f32::max)
            / R
    };
    let (a, b) = (bump(&own), bump(&mean));
    assert!(a > 0.1, "the bump stands {a} r");
    assert!(
        b < 0.4 * a,
        "the mean's bump stands {b} r, the frame's own {a} r"
    );
}

/// The averaged surface is the same to the bit on one thread and on four.
#[test]
fn the_mean_does_not_depend_on_the_thread_count() {
    let ball = lattice_ball(Vec3::splat(0.3), 5.0 * R, R);
    let side = |seed: u64| -> Vec<Vec3> {
        let mut next = uniform(seed);
        let step = Vec3::new(0.2 * R, 0.0, 0.0);
        ball.iter()
            .map(|p| *p + step + (uniform_point(&mut next) - 0.5) * 0.2 * R)
            .collect()
    };
    let (before, after) = (side(9), side(10));
    let meshes = [1, 4].map(|threads| {
        let rec = reconstructor("ssp07", Some(threads));
        along_flow(&rec, &ball, &before, &after)
    });
    let bits = |m: &TriMesh| -> Vec<[u32; 3]> {
        m.vertices
            .iter()
            .map(|v| v.to_array().map(f32::to_bits))
            .collect()
    };
    assert!(meshes[0].triangles == meshes[1].triangles);
    assert!(bits(&meshes[0]) == bits(&meshes[1]));
}

/// Deferring frame t's values far from its surface (on CPUs where it pays) leaves the averaged
/// mesh as it is to the bit: every value a crossed edge reads is sampled before it is averaged.
#[test]
fn deferring_values_keeps_the_averaged_mesh_to_the_bit() {
    use crate::recon::stages::deferred_values::tests::DEFER;
    let ball = lattice_ball(Vec3::splat(0.3), 5.0 * R, R);
    let side = |seed: u64, k: f32| -> Vec<Vec3> {
        let mut next = uniform(seed);
        let step = Vec3::new(0.3, 0.1, 0.0) * R * k;
        ball.iter()
            .map(|p| *p + step + (uniform_point(&mut next) - 0.5) * 0.2 * R)
            .collect()
    };
    let (before, after) = (side(3, -1.0), side(4, 1.0));
    let moves = |s: &[Vec3]| -> Vec<Option<Vec3>> {
        ball.iter().zip(s).map(|(a, b)| Some(*b - *a)).collect()
    };
    let (back, ahead) = (moves(&before), moves(&after));
    let params = crate::tests::common::params(R, "r/2");
    // Each frame's field sampled as it defers, the sides' left-out corners sampled by the mean.
    let run = |defer: bool| {
        DEFER.set(Some(defer));
        let fields = [&ball, &before, &after]
            .map(|p| crate::recon::sample(p, &params, None).unwrap().unwrap());
        let sides = Sides {
            fields: [&fields[1], &fields[2]],
            moves: [&back, &ahead],
        };
        let out = crate::recon::reconstruct_along_flow(
            &ball,
            Some(&fields[0]),
            Some(&sides),
            &params,
            None,
        );
        DEFER.set(None);
        out.unwrap()
    };
    let (all, deferred) = (run(false), run(true));
    assert!(deferred.stats.deferred_values > 0 && all.stats.deferred_values == 0);
    assert!(deferred.stats.flow_mean_vertices == all.stats.flow_mean_vertices);
    let bits = |m: &TriMesh| -> Vec<[u32; 3]> {
        m.vertices
            .iter()
            .map(|v| v.to_array().map(f32::to_bits))
            .collect()
    };
    assert!(deferred.mesh.triangles == all.mesh.triangles);
    assert!(bits(&deferred.mesh) == bits(&all.mesh));
}
