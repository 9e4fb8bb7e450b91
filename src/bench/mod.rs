//! `splash bench`: its arguments, and the paper's comparison of the engines (`engines.rs`,
//! `tables.rs`); the other papers' benches are `iso.rs`, `preview.rs`, `slices.rs` and
//! `temporal.rs`. Nothing here is on `splash recon`'s path.

mod engines;
mod iso;
mod preview;
mod rigid;
mod slices;
mod tables;
mod temporal;

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand};

use splash_sph::{Bytes, Config, Engine, Length};

use engines::Options;

#[derive(Args)]
#[command(after_help = "\
Each scene is a directory of particle frames (or frame files, grouped by their directory). Every
frame is reconstructed at every --cell by the scatter (serial), the full gather and the narrow
band (at every --threads count), each run in its own thread pool. Runs whose full grid would
need more than --max-memory are not attempted and read NA in the tables, with the reason.

`splash bench iso FRAME`, `splash bench preview FRAME` and `splash bench slices FRAME` print the
Marching Correctors', the Fitted BVH's and Marching Slices' tables instead (see their --help).

Example:
  splash bench preview fixtures/frame_0040.ply --spacing 0.014 --threads 2
  splash bench ../shared/data/cbd-small --frames-per-scene 3 --spacing 0.014 --cell r --cell r/2 --threads 1,2")]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct BenchArgs {
    /// Another paper's tables instead of the engines'.
    #[command(subcommand)]
    table: Option<BenchTable>,

    /// Scene directories or particle files.
    #[arg(required = true)]
    inputs: Vec<PathBuf>,

    /// Cell sizes (repeat): 2r, r, r/2 or lengths. Default: r and r/2, as the paper.
    #[arg(long)]
    cell: Vec<String>,

    /// Thread counts, comma-separated. Default: 1 and all cores.
    #[arg(long, value_delimiter = ',')]
    threads: Vec<usize>,

    /// Particle spacing r: one for all scenes, or repeated once per scene in order. Estimated
    /// from each scene's first frame when absent.
    #[arg(long)]
    spacing: Vec<f32>,

    /// Frames per scene, spread evenly over its files. Default: all.
    #[arg(long)]
    frames_per_scene: Option<usize>,

    /// Engines to compare, comma-separated: scatter, full-gather, narrow-band, slices.
    /// Default: the paper's three, scatter,full-gather,narrow-band.
    #[arg(long, value_delimiter = ',')]
    engines: Vec<String>,

    /// Memory a full-grid engine may use (e.g. 8G); larger runs read NA. Default: half the
    /// machine's memory.
    #[arg(long)]
    max_memory: Option<String>,

    /// TOML file with the reconstruction parameters (see configs/).
    #[arg(long)]
    config: Option<PathBuf>,

    /// Where the raw records go (JSON).
    #[arg(long, default_value = "bench.json")]
    json: PathBuf,

    /// Also write the tables to this Markdown file.
    #[arg(long)]
    markdown: Option<PathBuf>,

    /// Print only the tables.
    #[arg(short, long)]
    quiet: bool,
}

/// The other papers' benches.
#[derive(Subcommand)]
enum BenchTable {
    /// Marching Correctors' Tables I–V on one frame: stage times at kernel scales 1, 0.75,
    /// 0.5 and cells r/2, r with and without correction, for the vorticity, |v| and λ2.
    Iso(iso::BenchIsoArgs),
    /// Fitted BVH's ablations (Gourmel et al. 2010, Tables 3-5 in shape): each part switched
    /// off, and the plain BVH, on a 640x360 render of one frame.
    Preview(preview::BenchPreviewArgs),
    /// Marching Slices' Fig. 7 (Rosenberg & Birdwell 2008): the slices engine against
    /// surface-following Marching Cubes in blocks and with hash maps, time and memory.
    Slices(slices::BenchSlicesArgs),
    /// Jitter of whole sequences (issue 38): raw, default, your variants and the peer on
    /// consecutive frames, measured against the fluid's own motion, with time and memory.
    Temporal(temporal::BenchTemporalArgs),
}

pub fn bench(args: BenchArgs) -> Result<ExitCode> {
    match args.table {
        Some(BenchTable::Iso(iso)) => return iso::run(iso),
        Some(BenchTable::Preview(preview)) => return preview::run(preview),
        Some(BenchTable::Slices(slices)) => return slices::run(slices),
        Some(BenchTable::Temporal(temporal)) => return temporal::run(temporal),
        None => {}
    }
    let mut config = match &args.config {
        Some(path) => Config::from_file(path)?,
        None => Config::default(),
    };
    if let Some(m) = &args.max_memory {
        config.max_memory = Some(Bytes::parse(m).context("--max-memory")?);
    }
    let cells = if args.cell.is_empty() {
        vec![Length::Spacings(1.0), Length::Spacings(0.5)]
    } else {
        args.cell
            .iter()
            .map(|c| Length::parse(c).context("--cell"))
            .collect::<Result<_>>()?
    };
    let threads = if args.threads.is_empty() {
        let all = std::thread::available_parallelism().map_or(1, |n| n.get());
        if all > 1 { vec![1, all] } else { vec![1] }
    } else {
        args.threads.clone()
    };
    let engines = if args.engines.is_empty() {
        vec![Engine::Scatter, Engine::FullGather, Engine::NarrowBand]
    } else {
        args.engines
            .iter()
            .map(|e| Engine::parse(e).context("--engines"))
            .collect::<Result<_>>()?
    };
    if args.spacing.iter().any(|r| !(r.is_finite() && *r > 0.0)) {
        bail!("--spacing must be positive");
    }
    let opts = Options {
        inputs: args.inputs,
        cells,
        threads,
        spacings: args.spacing,
        frames_per_scene: args.frames_per_scene,
        engines,
        config,
    };
    let quiet = args.quiet;
    let report = engines::run(&opts, |line| {
        if !quiet {
            eprintln!("{line}");
        }
    })?;
    let text = serde_json::to_string_pretty(&report)? + "\n";
    std::fs::write(&args.json, text)
        .with_context(|| format!("{}: cannot write the records", args.json.display()))?;
    let tables = tables::markdown(&report);
    if let Some(path) = &args.markdown {
        std::fs::write(path, &tables)
            .with_context(|| format!("{}: cannot write the tables", path.display()))?;
    }
    print!("{tables}");
    if !quiet {
        eprintln!("raw records: {}", args.json.display());
    }
    Ok(ExitCode::SUCCESS)
}
