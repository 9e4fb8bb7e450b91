//! Times each stage of the post-processing (issue 25) on one frame's raw mesh, the best of
//! several runs per stage: the CPU time on one thread (steady on a loaded machine) and the wall
//! time on two, to show where the default `[post]` spends its time.
//!
//! `cargo run --release --example post_stages -- FRAME.ply SPACING [REFINE_DEGREES] [RUNS]`

use splash_sph::mesh::adjacency::{Neighbours, VertexFaces};
use splash_sph::mesh::post::refinement::refine_bends;
use splash_sph::mesh::post::smoothing::{relax_tangentially, taubin};
use splash_sph::mesh::post::volume::{
    Components, Measures, normals_and_measures, particles_inside,
};
use splash_sph::mesh::post::{PostConfig, postprocess};
use splash_sph::{Config, Length, Reconstructor, Vec3, read_particles};
use std::time::Instant;

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

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [frame, spacing, ..] = args.as_slice() else {
        return Err("usage: post_stages FRAME.ply SPACING [REFINE_DEGREES] [RUNS]".into());
    };
    let spacing: f32 = spacing.parse()?;
    let refine: f32 = args.get(2).map_or(Ok(20.0), |a| a.parse())?;
    let runs: usize = args.get(3).map_or(Ok(5), |a| a.parse())?;
    let particles = read_particles(frame.as_ref(), None)?.positions;
    let mut config = Config {
        spacing: Some(spacing),
        cell: Length::Spacings(0.5),
        ..Config::default()
    };
    config.post.raw = true;
    let raw = Reconstructor::new(config)?.reconstruct(&particles)?.mesh;
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
    Ok(())
}
