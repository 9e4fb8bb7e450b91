//! The time of each stage of the post-processing (issue 25) on one frame's raw mesh, the best
//! of several runs per stage: the CPU time on one thread (steady on a loaded machine) and the
//! wall time on two, to show where the default `[post]` spends its time. A measurement of the
//! stages inside `postprocess`, not a check, so ignored by default:
//!
//! `cargo test --release -p splash-sph --lib post_stage_times -- --ignored --nocapture`
//!
//! times `fixtures/frame_0040.ply` at spacing 0.014; `SPLASH_FRAME` and `SPLASH_SPACING` give
//! another frame, `SPLASH_REFINE` the refinement's angle in degrees (default 20) and
//! `SPLASH_RUNS` the runs per stage (default 5).

use std::time::Instant;

use glam::Vec3;

use crate::mesh::adjacency::{Neighbours, VertexFaces};
use crate::mesh::post::refinement::refine_bends;
use crate::mesh::post::smoothing::{relax_tangentially, taubin};
use crate::mesh::post::volume::{Components, Measures, normals_and_measures, particles_inside};
use crate::mesh::post::{PostConfig, postprocess};
use crate::tests::common::fixture;
use crate::{Config, Length, Reconstructor, read_particles};

/// The process's CPU time, in ms.
fn cpu_ms() -> f64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid timespec to write to.
    unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut t) };
    t.tv_sec as f64 * 1e3 + t.tv_nsec as f64 * 1e-6
}

/// The best (CPU, wall) times of `runs` calls of `f` on a fresh `setup()`, in ms.
fn best<S>(runs: usize, mut setup: impl FnMut() -> S, mut f: impl FnMut(&mut S)) -> (f64, f64) {
    (0..runs)
        .map(|_| {
            let mut s = setup();
            let (c, t) = (cpu_ms(), Instant::now());
            f(&mut s);
            (cpu_ms() - c, t.elapsed().as_secs_f64() * 1e3)
        })
        .fold((f64::INFINITY, f64::INFINITY), |a, b| {
            (a.0.min(b.0), a.1.min(b.1))
        })
}

/// The environment variable `name` parsed, else `default`.
fn setting<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name).map_or(default, |v| {
        v.parse()
            .unwrap_or_else(|_| panic!("{name}={v}: not a number"))
    })
}

#[test]
#[ignore = "a measurement: run with --ignored --nocapture"]
fn post_stage_times() {
    let frame = std::env::var("SPLASH_FRAME")
        .map_or_else(|_| fixture("frame_0040.ply"), std::path::PathBuf::from);
    let spacing: f32 = setting("SPLASH_SPACING", 0.014);
    let refine: f32 = setting("SPLASH_REFINE", 20.0);
    let runs: usize = setting("SPLASH_RUNS", 5);
    let particles = read_particles(&frame, None).unwrap().positions;
    let frame = frame.display();
    let mut config = Config {
        spacing: Some(spacing),
        cell: Length::Spacings(0.5),
        ..Config::default()
    };
    config.post.raw = true;
    let raw = Reconstructor::new(config)
        .unwrap()
        .reconstruct(&particles)
        .unwrap()
        .mesh;
    let cell = 0.5 * spacing;
    let (v, t) = (raw.vertices.len(), raw.triangles.len());
    println!("{frame}: {v} vertices, {t} triangles; best of {runs} runs, ms");
    println!("| stage | CPU, 1 thread | wall, 2 threads |\n|---|---:|---:|");
    let rings = VertexFaces::new(v, &raw.triangles);
    let neighbours = Neighbours::new(rings.clone(), &raw.triangles);
    let components = Components::new(&neighbours);
    let volumes = components.volumes_and_areas(&raw.vertices, &raw.triangles);
    let mut normals = vec![Vec3::ZERO; v];
    let mut measures = Measures::default();
    normals_and_measures(
        &raw.vertices,
        &raw.triangles,
        &rings,
        &components,
        &mut normals,
        &mut measures,
    );
    let posts = [
        ("post, default".to_string(), PostConfig::default()),
        (
            format!("post, refine_angle {refine}"),
            PostConfig {
                refine_angle: refine,
                ..PostConfig::default()
            },
        ),
        (
            "post, refine_angle 0".to_string(),
            PostConfig {
                refine_angle: 0.0,
                ..PostConfig::default()
            },
        ),
    ];
    type Stage<'a> = (&'a str, Box<dyn Fn() -> (f64, f64) + Sync + 'a>);
    let mut stages: Vec<Stage> = vec![
        (
            "vertex rows",
            Box::new(|| best(runs, || (), |_| drop(VertexFaces::new(v, &raw.triangles)))),
        ),
        (
            "neighbours",
            Box::new(|| {
                best(
                    runs,
                    || rings.clone(),
                    |r| drop(Neighbours::new(std::mem::take(r), &raw.triangles)),
                )
            }),
        ),
        (
            "components",
            Box::new(|| best(runs, || (), |_| drop(Components::new(&neighbours)))),
        ),
        (
            "volumes and areas",
            Box::new(|| {
                best(
                    runs,
                    || (),
                    |_| drop(components.volumes_and_areas(&raw.vertices, &raw.triangles)),
                )
            }),
        ),
        (
            "particles inside",
            Box::new(|| {
                best(
                    runs,
                    || (),
                    |_| {
                        drop(particles_inside(
                            &components,
                            &volumes,
                            &raw.vertices,
                            &raw.triangles,
                            &particles,
                            cell,
                        ))
                    },
                )
            }),
        ),
        (
            "one λ|μ pair",
            Box::new(|| {
                best(
                    runs,
                    || (raw.vertices.clone(), vec![Vec3::ZERO; v]),
                    |(p, s)| taubin(p, s, &neighbours, 1, 0.6, -0.64),
                )
            }),
        ),
        (
            "normals and measures",
            Box::new(|| {
                best(
                    runs,
                    // Warm buffers, as the post's later calls find them.
                    || (vec![Vec3::ZERO; v], measures.clone()),
                    |(n, m)| {
                        normals_and_measures(
                            &raw.vertices,
                            &raw.triangles,
                            &rings,
                            &components,
                            n,
                            m,
                        )
                    },
                )
            }),
        ),
        (
            "one relaxation step",
            Box::new(|| {
                best(
                    runs,
                    || (raw.vertices.clone(), vec![Vec3::ZERO; v]),
                    |(p, s)| relax_tangentially(p, s, &normals, &neighbours, 1, 0.5),
                )
            }),
        ),
        (
            "refinement",
            Box::new(|| {
                best(
                    runs,
                    || {
                        (
                            raw.vertices.clone(),
                            normals.clone(),
                            raw.triangles.clone(),
                            rings.clone(),
                        )
                    },
                    |(p, n, t, r)| {
                        drop(refine_bends(
                            p,
                            n,
                            t,
                            std::mem::take(r),
                            refine.to_radians(),
                        ))
                    },
                )
            }),
        ),
    ];
    for (name, config) in &posts {
        stages.push((
            name,
            Box::new(|| {
                best(
                    runs,
                    || raw.clone(),
                    |m| postprocess(m, &particles, spacing, cell, config, true).unwrap(),
                )
            }),
        ));
    }
    let pools: Vec<_> = [1, 2]
        .map(|n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .unwrap()
        })
        .into();
    for (name, stage) in &stages {
        let [(one, _), (_, two)] = [0, 1].map(|i| pools[i].install(stage));
        println!("| {name} | {one:.1} | {two:.1} |");
    }
}
