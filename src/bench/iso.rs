//! `splash bench iso`: the Marching Correctors paper's Tables I–V (Schindler et al., Sec. IV) on
//! one frame: stage times at kernel scales 1, 0.75, 0.5 and virtual cells r/2 and r (0.5h and
//! h), with and without the correction, for the vorticity (Table I), a scalar (Table II: |v|,
//! since SPH frames seldom carry pressure) and λ2 (Table III); the cells used (IV) and the
//! correction sizes (V).

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use anyhow::{Context, Result, bail};
use clap::Args;
use serde::Serialize;

use splash_sph::iso::{Derived, IsoRequest, IsoStats, extract};
use splash_sph::{Config, Length, estimate_spacing};

use splash_sph::report::{Build, Machine};

#[derive(Args)]
#[command(after_help = "\
Every quantity is extracted at kernel scales 1, 0.75 and 0.5 and cells r/2 and r, once with 0
and once with 3 Newton steps, each --repeat times (the fastest kept), in a pool of --threads
(the paper: one core). Example:
  splash bench iso fixtures/frame_0040.ply --spacing 0.014")]
pub struct BenchIsoArgs {
    /// The particle frame (with a velocity attribute).
    frame: PathBuf,

    /// Particle spacing r; estimated from the frame when absent.
    #[arg(long)]
    spacing: Option<f32>,

    /// Worker threads of every run.
    #[arg(long, default_value_t = 1)]
    threads: usize,

    /// Runs per configuration; the fastest is kept (the counts do not change).
    #[arg(long, default_value_t = 1)]
    repeat: usize,

    /// Level of the vorticity |curl v| (Table I).
    #[arg(long, default_value_t = 20.0)]
    vorticity_level: f32,

    /// Level of the speed |v| (Table II, "speed").
    #[arg(long, default_value_t = 1.5)]
    speed_level: f32,

    /// Level of λ2 (Table III).
    #[arg(long, default_value_t = -50.0, allow_hyphen_values = true)]
    lambda2_level: f32,

    /// Where the raw records go (JSON).
    #[arg(long, default_value = "bench-iso.json")]
    json: PathBuf,

    /// Also write the tables to this Markdown file.
    #[arg(long)]
    markdown: Option<PathBuf>,

    /// Print only the tables.
    #[arg(short, long)]
    quiet: bool,
}

const SCALES: [f32; 3] = [1.0, 0.75, 0.5];
const CELLS: [(&str, f32); 2] = [("r/2", 0.5), ("r", 1.0)];
const CORRECT: u32 = 3;

/// One extraction: what was asked, its figures, and its stage times in seconds.
#[derive(Debug, Clone, Serialize)]
pub struct IsoRun {
    pub quantity: String,
    pub level: f32,
    pub kernel_scale: f32,
    pub cell: String,
    pub correct: u32,
    pub threads: usize,
    pub seconds: Seconds,
    pub stats: IsoStats,
}

/// Stage times (the paper's rows).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Seconds {
    pub grid_construction: f64,
    pub seed_cells: f64,
    /// Surface following, vertex placement (and correction), trimming and normals.
    pub surface_extraction: f64,
    /// Without the grid construction, a preprocessing step (Table II's totals).
    pub total: f64,
}

impl Seconds {
    fn of(s: &IsoStats) -> Seconds {
        let t = &s.timings;
        let sec = Duration::as_secs_f64;
        Seconds {
            grid_construction: sec(&t.grid_construction),
            seed_cells: sec(&t.seed_cells),
            surface_extraction: sec(&(t.surface_extraction + t.correction + t.finishing)),
            total: sec(&s.total()),
        }
    }
}

#[derive(Debug, Serialize)]
struct IsoBenchReport {
    machine: Machine,
    build: Build,
    frame: String,
    particles: usize,
    spacing: f32,
    runs: Vec<IsoRun>,
}

pub fn run(args: BenchIsoArgs) -> Result<ExitCode> {
    if args.threads == 0 || args.repeat == 0 {
        bail!("--threads and --repeat must be at least 1");
    }
    let particles = splash_sph::io::read_particles(&args.frame, None)?;
    let r = match args.spacing {
        Some(r) if r.is_finite() && r > 0.0 => r,
        Some(r) => bail!("--spacing must be positive, got {r}"),
        None => estimate_spacing(&particles.positions).with_context(|| {
            format!(
                "{}: cannot estimate the spacing; give --spacing",
                args.frame.display()
            )
        })?,
    };
    let quantities = [
        ("vorticity", Derived::Vorticity, args.vorticity_level),
        ("speed", Derived::Magnitude, args.speed_level),
        ("λ2", Derived::Lambda2, args.lambda2_level),
    ];
    let mut runs = Vec::new();
    for &(name, derived, level) in &quantities {
        let request = IsoRequest {
            attribute: "velocity".into(),
            derived,
            level,
        };
        for scale in SCALES {
            for (label, cell) in CELLS {
                for correct in [0, CORRECT] {
                    let mut config = Config {
                        spacing: Some(r),
                        cell: Length::Spacings(cell),
                        threads: Some(args.threads),
                        ..Config::default()
                    };
                    config.iso.kernel_scale = scale;
                    config.iso.correct = correct;
                    let mut best: Option<IsoStats> = None;
                    for _ in 0..args.repeat {
                        let s = extract(
                            &particles.positions,
                            particles.attributes.clone(),
                            &request,
                            &config,
                        )
                        .with_context(|| format!("{}", args.frame.display()))?
                        .stats;
                        let total = |s: &IsoStats| s.total() + s.timings.grid_construction;
                        if best.as_ref().is_none_or(|b| total(&s) < total(b)) {
                            best = Some(s);
                        }
                    }
                    let stats = best.expect("at least one repeat");
                    if !args.quiet {
                        eprintln!(
                            "{name} = {level}, scale {scale}, cell {label}, correct {correct}: {} \
                             triangles, {:.1} ms",
                            stats.triangles,
                            1e3 * (stats.total() + stats.timings.grid_construction).as_secs_f64()
                        );
                    }
                    runs.push(IsoRun {
                        quantity: name.into(),
                        level,
                        kernel_scale: scale,
                        cell: label.into(),
                        correct,
                        threads: args.threads,
                        seconds: Seconds::of(&stats),
                        stats,
                    });
                }
            }
        }
    }
    let report = IsoBenchReport {
        machine: Machine::this(),
        build: crate::this_build(),
        frame: args.frame.display().to_string(),
        particles: particles.positions.len(),
        spacing: r,
        runs,
    };
    let text = serde_json::to_string_pretty(&report)? + "\n";
    std::fs::write(&args.json, text)
        .with_context(|| format!("{}: cannot write the records", args.json.display()))?;
    let tables = markdown(&report);
    if let Some(path) = &args.markdown {
        std::fs::write(path, &tables)
            .with_context(|| format!("{}: cannot write the tables", path.display()))?;
    }
    print!("{tables}");
    if !args.quiet {
        eprintln!("raw records: {}", args.json.display());
    }
    Ok(ExitCode::SUCCESS)
}

fn find<'a>(runs: &'a [IsoRun], q: &str, scale: f32, cell: &str, correct: u32) -> &'a IsoRun {
    runs.iter()
        .find(|r| {
            r.quantity == q && r.kernel_scale == scale && r.cell == cell && r.correct == correct
        })
        .expect("every configuration was run")
}

fn row(out: &mut String, name: &str, cells: impl Iterator<Item = String>) {
    out.push_str(&format!("| {name} |"));
    for c in cells {
        out.push_str(&format!(" {c} |"));
    }
    out.push('\n');
}

/// The tables in the paper's shape, times in milliseconds.
fn markdown(report: &IsoBenchReport) -> String {
    let runs = &report.runs;
    let ms = |s: f64| format!("{:.1}", 1e3 * s);
    let mut out = format!(
        "splash bench iso: {} ({} particles, r = {}), {} thread(s); times in ms, the fastest \
         of the repeats\n",
        report.frame,
        report.particles,
        report.spacing,
        runs.first().map_or(1, |r| r.threads)
    );
    let columns: Vec<(f32, &str)> = SCALES
        .iter()
        .flat_map(|&s| CELLS.iter().map(move |&(c, _)| (s, c)))
        .collect();
    for (number, q) in ["vorticity", "speed", "λ2"].iter().enumerate() {
        let level = runs
            .iter()
            .find(|r| r.quantity == *q)
            .map_or(0.0, |r| r.level);
        let roman = ["I", "II", "III"][number];
        out.push_str(&format!(
            "\nTable {roman}: computing time for a {q} isosurface ({q} = {level})\n\n"
        ));
        row(
            &mut out,
            "h scaling factor",
            columns.iter().map(|c| c.0.to_string()),
        );
        row(
            &mut out,
            "Grid size",
            columns.iter().map(|c| c.1.to_string()),
        );
        row(&mut out, "---", columns.iter().map(|_| "---".into()));
        let at = |c: &(f32, &str), k| find(runs, q, c.0, c.1, k);
        let line = |out: &mut String, name, k, f: &dyn Fn(&IsoRun) -> String| {
            row(out, name, columns.iter().map(|c| f(at(c, k))));
        };
        line(&mut out, "Grid construction", CORRECT, &|r| {
            ms(r.seconds.grid_construction)
        });
        line(&mut out, "Seed cell selection", CORRECT, &|r| {
            ms(r.seconds.seed_cells)
        });
        line(&mut out, "Surface extraction", 0, &|r| {
            ms(r.seconds.surface_extraction)
        });
        line(&mut out, "S.e. with correction", CORRECT, &|r| {
            ms(r.seconds.surface_extraction)
        });
        line(&mut out, "Total w/o corr.", 0, &|r| ms(r.seconds.total));
        line(&mut out, "Total with corr.", CORRECT, &|r| {
            ms(r.seconds.total)
        });
        line(&mut out, "Triangles", CORRECT, &|r| {
            r.stats.triangles.to_string()
        });
        line(&mut out, "Neighbours in a support", CORRECT, &|r| {
            format!("{:.1}", r.stats.support_neighbours)
        });
    }
    let full: Vec<(&str, &str)> = ["vorticity", "speed", "λ2"]
        .iter()
        .flat_map(|&q| CELLS.iter().map(move |&(c, _)| (q, c)))
        .collect();
    out.push_str("\nTable IV: virtual grid cells and cells used (kernel scale 1, corrected)\n\n");
    row(&mut out, "Quantity", full.iter().map(|c| c.0.to_string()));
    row(&mut out, "Grid size", full.iter().map(|c| c.1.to_string()));
    row(&mut out, "---", full.iter().map(|_| "---".into()));
    let stat = |out: &mut String, name, f: &dyn Fn(&IsoStats) -> String| {
        row(
            out,
            name,
            full.iter()
                .map(|c| f(&find(runs, c.0, 1.0, c.1, CORRECT).stats)),
        );
    };
    stat(&mut out, "Virtual cells", &|s| s.virtual_cells.to_string());
    stat(&mut out, "Seed cells", &|s| s.seed_cells.to_string());
    stat(&mut out, "Non-intersected cells", &|s| {
        (s.visited_cells - s.crossed_cells).to_string()
    });
    stat(&mut out, "Total cells used", &|s| {
        s.crossed_cells.to_string()
    });
    stat(&mut out, "Isosurface triangles", &|s| {
        s.triangles.to_string()
    });
    stat(&mut out, "Cache hit ratio", &|s| {
        format!("{:.3}", s.cache_hit_ratio)
    });
    out.push_str("\nTable V: the correction step's moves (kernel scale 1, 3 Newton steps)\n\n");
    row(&mut out, "Quantity", full.iter().map(|c| c.0.to_string()));
    row(&mut out, "Grid size", full.iter().map(|c| c.1.to_string()));
    row(&mut out, "---", full.iter().map(|_| "---".into()));
    stat(&mut out, "Mean vector norm", &|s| {
        format!("{:.6}", s.correction.mean)
    });
    stat(&mut out, "Max vector norm", &|s| {
        format!("{:.6}", s.correction.max)
    });
    stat(&mut out, "St.dev. vector norm", &|s| {
        format!("{:.6}", s.correction.std_dev)
    });
    stat(&mut out, "Mean, % of the edge", &|s| {
        format!("{:.2}", 100.0 * s.correction.mean_fraction)
    });
    out
}
