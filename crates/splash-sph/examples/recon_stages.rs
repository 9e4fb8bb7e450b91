//! The CPU time of each reconstruction stage over a sequence, on one thread, the best of
//! several runs per frame: steady enough on a shared, loaded machine to compare two builds
//! (run it from each) where whole-process timings drift by more than the change.
//!
//! `cargo run --release --example recon_stages -- SPACING RUNS CONFIG.toml FRAME.ply…`

use std::time::Duration;

use splash_sph::{Config, Observer, Reconstructor, Stage, StageFigures, read_particles};

/// The process's CPU time.
fn cpu() -> Duration {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid timespec to write to.
    unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut t) };
    Duration::new(t.tv_sec as u64, t.tv_nsec as u32)
}

/// Stage times as CPU time (one thread: the work the stage did).
#[derive(Default)]
struct CpuClock {
    started: Option<Duration>,
}

impl Observer for CpuClock {
    fn stage_started(&mut self, _stage: Stage) {
        self.started = Some(cpu());
    }

    fn stage_finished(&mut self, _stage: Stage) -> StageFigures {
        StageFigures {
            time: self.started.take().map_or(Duration::ZERO, |t| cpu() - t),
            heap_peak: 0,
        }
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [spacing, runs, config, frames @ ..] = args.as_slice() else {
        return Err("usage: recon_stages SPACING RUNS CONFIG.toml FRAME.ply…".into());
    };
    let mut config = Config::from_file(config.as_ref())?;
    config.spacing = Some(spacing.parse()?);
    let runs: usize = runs.parse()?;
    let recon = Reconstructor::new(config)?;
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build_global()?;
    let names = ["sort", "t_sp", "band", "t_sf", "t_tri", "post"];
    let mut best_sum = [0.0f64; 6];
    for frame in frames {
        let particles = read_particles(frame.as_ref(), None)?.positions;
        let mut best = [f64::INFINITY; 6];
        for _ in 0..runs {
            let t = recon
                .reconstruct_observed(&particles, &mut CpuClock::default())?
                .stats
                .timings;
            let ms = [
                t.handler_array,
                t.surface_particles,
                t.band,
                t.scalar_field,
                t.triangulation,
                t.post,
            ]
            .map(|d| d.as_secs_f64() * 1e3);
            for (b, m) in best.iter_mut().zip(ms) {
                *b = b.min(m);
            }
        }
        for (s, b) in best_sum.iter_mut().zip(best) {
            *s += b;
        }
    }
    let total: f64 = best_sum.iter().sum();
    let row: Vec<String> = names
        .iter()
        .zip(best_sum)
        .map(|(n, ms)| format!("{n} {ms:.1}"))
        .collect();
    println!(
        "{} frames, best of {runs}, CPU ms: {}; total {total:.1}",
        frames.len(),
        row.join(", ")
    );
    Ok(())
}
