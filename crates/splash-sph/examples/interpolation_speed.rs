//! How long carrying the particles' velocity onto a reconstructed mesh takes
//! ([`Reconstructor::interpolate`]), with the minimum and median over the runs, and a checksum
//! of the result's bits, so that two builds can be checked to give the same values.
//!
//! `cargo run --release --example interpolation_speed -- FRAME.ply SPACING [CELL] [FIELD] [RUNS]`
//! (threads: `RAYON_NUM_THREADS`), e.g. `fixtures/frame_0040.ply 0.014 r/2 ssp07 20`: Blender's
//! render settings. The mesh is the default (post-processed) one.

use std::path::PathBuf;
use std::time::Instant;

use splash_sph::{Config, Length, Overrides, Reconstructor, read_particles};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "FRAME.ply SPACING [CELL] [FIELD] [RUNS]";
    let (Some(path), Some(spacing)) = (args.first(), args.get(1)) else {
        return Err(usage.into());
    };
    let particles = read_particles(&PathBuf::from(path), None)?;
    let velocity = particles
        .attributes
        .get("velocity")
        .ok_or("the frame has no velocity")?;
    let overrides = Overrides {
        spacing: Some(spacing.parse()?),
        cell: args.get(2).map(|c| Length::parse(c)).transpose()?,
        field: args.get(3).cloned(),
        ..Overrides::default()
    };
    let config = Config::default().apply(&overrides)?;
    let runs: usize = args.get(4).map_or(Ok(10), |r| r.parse())?;
    let reconstructor = Reconstructor::new(config)?;
    let mesh = reconstructor.reconstruct(&particles.positions)?.mesh;
    let mut times = Vec::with_capacity(runs);
    let mut checksum = 0u64;
    for _ in 0..runs {
        let start = Instant::now();
        let values = reconstructor.interpolate(&mesh, &particles.positions, velocity)?;
        times.push(start.elapsed());
        checksum = match values {
            splash_sph::Attribute::Vector(v) => v.iter().fold(0u64, |h, v| {
                [v.x, v.y, v.z]
                    .iter()
                    .fold(h, |h, c| h.rotate_left(5) ^ u64::from(c.to_bits()))
            }),
            splash_sph::Attribute::Scalar(_) => return Err("velocity became a scalar".into()),
        };
    }
    times.sort();
    println!(
        "{} particles, {} vertices: interpolation min {:.2} ms, median {:.2} ms over {runs} runs; \
         checksum {checksum:016x}",
        particles.positions.len(),
        mesh.vertices.len(),
        times[0].as_secs_f64() * 1e3,
        times[runs / 2].as_secs_f64() * 1e3,
    );
    Ok(())
}
