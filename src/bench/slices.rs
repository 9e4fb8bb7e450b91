//! `splash bench slices`: Fig. 7 of Rosenberg & Birdwell 2008 (Sec. 7) on the user's frame:
//! (1) the slices engine against its baselines, surface-following Marching Cubes (2) in blocks
//! with 3D corner arrays and a voxel-grid particle cache and (3) with hash maps, each with its
//! time, cubes and triangles per second, render and cache memory, and whether its mesh is the
//! slices engine's.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use clap::Args;

use splash_sph::{Baseline, Clock, Config, Engine, Length, Reconstruction, Reconstructor};
use splash_sph::{TriMesh, Vec3, estimate_spacing, read_particles};

#[derive(Args)]
#[command(after_help = "\
At every --cell the approaches reconstruct the frame in turn, --repeat times, in a pool of
--threads (the paper: one core); each keeps its fastest run by wall time. cpu is that run's CPU
time, which a busy machine does not lengthen: fps, cubes/s and tris/s are per CPU second. march
is the marching's wall time, without the stages all share. Meshes are raw (no post-processing).
Render memory is a block's corner caches at their peak (approach 3: the whole corner map), cache
memory its particle lookup structure and particle copies; \"in flight\" is the peak of both over
the run.
Example, the paper's metaball field (S = 1 and 0.75 are cells r/2 and 0.375r):
  splash bench slices fixtures/frame_0040.ply --spacing 0.014 --config configs/metaball.toml --cell r/2 --cell 0.375r")]
pub struct BenchSlicesArgs {
    /// The particle frame.
    frame: PathBuf,

    /// Particle spacing r; estimated from the frame when absent.
    #[arg(long)]
    spacing: Option<f32>,

    /// Cell sizes (repeat): r, r/2 or lengths. Default: r and r/2.
    #[arg(long)]
    cell: Vec<String>,

    /// Worker threads of every run (approach 3 marches on one whatever this is).
    #[arg(long, default_value_t = 1)]
    threads: usize,

    /// Runs per approach and cell; the fastest is kept (the counts do not change).
    #[arg(long, default_value_t = 3)]
    repeat: usize,

    /// TOML file with the reconstruction parameters (see configs/).
    #[arg(long)]
    config: Option<PathBuf>,

    /// Also write the tables to this Markdown file.
    #[arg(long)]
    markdown: Option<PathBuf>,
}

/// The approaches of Fig. 7, as the paper numbers them.
const APPROACHES: [(&str, Option<Baseline>); 3] = [
    ("1 marching slices, blocks, 2D-insert 1D-lookup cache", None),
    (
        "2 surface following, blocks, 3D arrays, voxel grid",
        Some(Baseline::BlockedCubes),
    ),
    (
        "3 surface following, hash maps",
        Some(Baseline::HashedCubes),
    ),
];

/// One approach's fastest run.
struct Row {
    name: &'static str,
    /// Wall time and the process's CPU time.
    time: Duration,
    cpu: Duration,
    rec: Reconstruction,
    mesh: &'static str,
}

pub fn run(args: BenchSlicesArgs) -> Result<ExitCode> {
    if args.threads == 0 || args.repeat == 0 {
        bail!("--threads and --repeat must be at least 1");
    }
    let mut config = match &args.config {
        Some(path) => Config::from_file(path)?,
        None => Config::default(),
    };
    let particles = read_particles(&args.frame, None)?;
    let points = particles.positions;
    config.spacing = match args.spacing.or(config.spacing) {
        Some(r) if r.is_finite() && r > 0.0 => Some(r),
        Some(r) => bail!("--spacing must be positive, got {r}"),
        None => Some(estimate_spacing(&points).with_context(|| {
            format!(
                "{}: cannot estimate the spacing; give --spacing",
                args.frame.display()
            )
        })?),
    };
    config.engine = Engine::Slices;
    config.threads = Some(args.threads);
    config.post.raw = true;
    let cells: Vec<String> = if args.cell.is_empty() {
        vec!["r".into(), "r/2".into()]
    } else {
        args.cell.clone()
    };
    let mut out = String::new();
    let mut differs = false;
    for label in &cells {
        config.cell = Length::parse(label).context("--cell")?;
        let rows = bench(&args.frame, &points, &config, args.repeat)?;
        differs |= rows.iter().any(|r| r.mesh == "DIFFERS");
        out.push_str(&table(&args.frame, points.len(), &config, label, &rows));
    }
    if let Some(path) = &args.markdown {
        std::fs::write(path, &out)
            .with_context(|| format!("{}: cannot write the tables", path.display()))?;
    }
    print!("{out}");
    Ok(if differs {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

/// Every approach at `config`'s cell, in turn `repeat` times (so that a drift of the shared
/// machine's speed falls on all alike), the fastest run of each kept.
fn bench(frame: &Path, points: &[Vec3], config: &Config, repeat: usize) -> Result<Vec<Row>> {
    let mut recons = Vec::new();
    for (_, baseline) in APPROACHES {
        let recon = Reconstructor::new(config.clone())?;
        recons.push(match baseline {
            Some(b) => recon.with_baseline(b),
            None => recon,
        });
    }
    let mut best: Vec<Option<(Duration, Duration, Reconstruction)>> = vec![None; recons.len()];
    for _ in 0..repeat {
        for (recon, best) in recons.iter().zip(&mut best) {
            let (start, cpu) = (Instant::now(), cpu_time());
            let rec = recon
                .reconstruct_observed(points, &mut Clock::default())
                .with_context(|| format!("{}", frame.display()))?;
            let (time, cpu) = (start.elapsed(), cpu_time().saturating_sub(cpu));
            if best.as_ref().is_none_or(|b| time < b.0) {
                *best = Some((time, cpu, rec));
            }
        }
    }
    let mut rows: Vec<Row> = Vec::new();
    for ((name, _), best) in APPROACHES.iter().zip(best) {
        let (time, cpu, rec) = best.expect("at least one run");
        let mesh = match rows.first() {
            None => "reference",
            Some(slices) if same_mesh(&slices.rec.mesh, &rec.mesh) => "same",
            Some(_) => "DIFFERS",
        };
        rows.push(Row {
            name,
            time,
            cpu,
            rec,
            mesh,
        });
    }
    Ok(rows)
}

/// CPU time of the process so far, all threads: with one worker, the run's own work, which
/// waiting for a busy machine's cores does not lengthen.
fn cpu_time() -> Duration {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid timespec for the call to fill.
    unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut t) };
    Duration::new(t.tv_sec as u64, t.tv_nsec as u32)
}

/// The same vertices (in order) and normals, and the same triangles in any order.
fn same_mesh(a: &TriMesh, b: &TriMesh) -> bool {
    let sorted = |m: &TriMesh| {
        let mut t: Vec<[u32; 3]> = m
            .triangles
            .iter()
            .map(|t| {
                let k = (0..3).min_by_key(|&i| t[i]).unwrap_or(0);
                [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
            })
            .collect();
        t.sort_unstable();
        t
    };
    a.vertices == b.vertices && a.normals == b.normals && sorted(a) == sorted(b)
}

/// Fig. 7's table for one cell, then the paper's ratios.
fn table(frame: &Path, particles: usize, config: &Config, cell: &str, rows: &[Row]) -> String {
    let mb = |b: usize| b as f64 / 1e6;
    let secs = |d: Duration| d.as_secs_f64();
    let first = &rows[0].rec.stats;
    let mut out = format!(
        "\nFig. 7 (shape): {}, {particles} particles, r = {}, field {}, cell {cell} = {:.3e}, {} \
         thread(s), fastest of the runs; fps, cubes/s and tris/s per CPU second\n\n",
        frame.display(),
        first.spacing,
        config.field.kind(),
        first.cell,
        first.threads,
    );
    out.push_str(
        "| approach | fps | time [ms] | cpu [ms] | march [ms] | cubes/s | tris/s | render mem \
         [MB] | cache mem [MB] | in flight [MB] | cubes | triangles | mesh |\n",
    );
    out.push_str("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n");
    for r in rows {
        let s = &r.rec.stats;
        let (t, cpu) = (secs(r.time), secs(r.cpu));
        out.push_str(&format!(
            "| {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.0} | {:.0} | {:.3} | {:.3} | {:.3} | {} | {} | {} |\n",
            r.name,
            1.0 / cpu,
            1e3 * t,
            1e3 * cpu,
            1e3 * secs(s.timings.scalar_field),
            s.surface_cells as f64 / cpu,
            s.triangles as f64 / cpu,
            mb(s.slices.render_bytes_max),
            mb(s.slices.cache_bytes_max),
            mb(s.slices.in_flight_peak),
            s.surface_cells,
            s.triangles,
            r.mesh,
        ));
    }
    let memory =
        |r: &Row| (r.rec.stats.slices.render_bytes_max + r.rec.stats.slices.cache_bytes_max) as f64;
    out.push('\n');
    for other in &rows[1..] {
        out.push_str(&format!(
            "slices vs ({}): {:.2}× as fast in CPU time ({:.2}× in wall time), {:.2}× less \
             memory (render + cache; render {:.2}×, cache {:.2}×)\n",
            &other.name[..1],
            secs(other.cpu) / secs(rows[0].cpu),
            secs(other.time) / secs(rows[0].time),
            memory(other) / memory(&rows[0]),
            other.rec.stats.slices.render_bytes_max as f64 / first.slices.render_bytes_max as f64,
            other.rec.stats.slices.cache_bytes_max as f64 / first.slices.cache_bytes_max as f64,
        ));
    }
    out
}
