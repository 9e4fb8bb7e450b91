//! The `splash` command: parses arguments and hands the work to the library.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clap::{Args, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};

use splash::batch::{Batch, FrameOutcome, Output, Progress};
use splash::config::{Config, Length};
use splash::field::FieldConfig;
use splash::io::{InputFormat, MeshFormat};
use splash::recon::Engine;

#[derive(Parser)]
#[command(
    name = "splash",
    version,
    about = "Triangle meshes from SPH particle frames (Akinci et al. 2012)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Reconstruct one surface mesh per particle file.
    Recon(Recon),
    /// Inspect configurations.
    #[command(subcommand)]
    Config(ConfigCommand),
}

#[derive(Subcommand)]
enum ConfigCommand {
    /// Print the full configuration that the given file and flags resolve to, as TOML.
    Show(ConfigArgs),
}

/// The reconstruction parameters: built-in defaults, overridden by the config file, overridden
/// by these flags.
#[derive(Args)]
struct ConfigArgs {
    /// TOML file with the reconstruction parameters (see configs/).
    #[arg(long)]
    config: Option<PathBuf>,

    /// Scalar field, with its defaults unless the config file sets the same kind: ssp07
    /// (default), zb05, density, blobby or metaball.
    #[arg(long)]
    field: Option<String>,

    /// Particle spacing r (the simulator's equilibrium distance). Estimated from the first
    /// frame when neither this nor --particle-radius is given.
    #[arg(long, conflicts_with = "particle_radius")]
    spacing: Option<f32>,

    /// Particle radius as SPlisHSPlasH and splashsurf give it: r = 2 × radius.
    #[arg(long)]
    particle_radius: Option<f32>,

    /// Marching Cubes cell size: 2r, r, r/2 (default), or a length.
    #[arg(long)]
    cell: Option<String>,
}

impl ConfigArgs {
    fn resolve(&self) -> Result<Config> {
        let mut config = match &self.config {
            Some(path) => Config::from_file(path)?,
            None => Config::default(),
        };
        if let Some(kind) = &self.field
            && config.field.kind() != kind
        {
            config.field = FieldConfig::named(kind)?;
        }
        if let Some(r) = self.spacing {
            config.spacing = Some(r);
        }
        if let Some(p) = self.particle_radius {
            config.spacing = Some(2.0 * p);
        }
        if let Some(c) = &self.cell {
            config.cell = Length::parse(c).context("--cell")?;
        }
        config.validate()?;
        Ok(config)
    }
}

#[derive(Args)]
#[command(after_help = "\
Inputs: PLY (ascii or binary; the vertex element's x, y, z), CSV (x, y, z columns by header name,
or the first three columns without a header) and raw binary (.bin/.raw: little-endian f32 x y z
triples, nothing else). The format comes from the extension unless --input-format is given.

Lengths (--cell, band and support in the config) are multiples of the particle spacing r
(2r, r, r/2, 0.5r) or plain numbers in world units. The band of surface vertices spans 2r
around each surface particle, widened to r + cell when that is larger (3r at cell 2r), and it
grows by itself wherever the surface leaves it, so meshes are closed at every cell size.")]
struct Recon {
    /// Particle files, one per frame.
    #[arg(required = true)]
    inputs: Vec<PathBuf>,

    /// Output: a directory (ending in /), a file for a single input, or a pattern with {stem}
    /// or {frame} / {frame:04}. Default: {stem}_surface.obj beside each input.
    #[arg(short, long)]
    output: Option<String>,

    #[command(flatten)]
    params: ConfigArgs,

    /// Mesh format: obj, ply (binary little-endian) or ply-ascii. Default: from the output
    /// file's extension, else obj.
    #[arg(long)]
    format: Option<String>,

    /// Input format for every file: ply, csv or raw.
    #[arg(long)]
    input_format: Option<String>,

    /// Worker threads (default: all cores). The mesh does not depend on it.
    #[arg(long)]
    threads: Option<usize>,

    /// Print stage times and counts per frame.
    #[arg(short, long)]
    verbose: bool,

    /// Print only errors.
    #[arg(short, long, conflicts_with = "verbose")]
    quiet: bool,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Recon(args) => recon(args),
        Command::Config(ConfigCommand::Show(args)) => show_config(&args),
    };
    result.unwrap_or_else(|e| {
        eprintln!("error: {e:#}");
        ExitCode::FAILURE
    })
}

fn show_config(args: &ConfigArgs) -> Result<ExitCode> {
    let config = args.resolve()?;
    print!(
        "{}",
        toml::to_string(&config).context("cannot write the configuration as TOML")?
    );
    Ok(ExitCode::SUCCESS)
}

fn recon(args: Recon) -> Result<ExitCode> {
    if let Some(n) = args.threads {
        if n == 0 {
            bail!("--threads must be at least 1");
        }
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .context("cannot start the worker threads")?;
    }
    let config = args.params.resolve()?;
    let output = args
        .output
        .as_deref()
        .map_or(Output::BesideInput, Output::parse);
    let format = match (&args.format, output.format_hint()) {
        (Some(f), hint) => {
            let format = MeshFormat::parse(f)?;
            if let Some(hint) = hint.filter(|h| h.extension() != format.extension()) {
                bail!(
                    "--format {f} does not match the output name's .{} extension",
                    hint.extension()
                );
            }
            format
        }
        (None, hint) => hint.unwrap_or(MeshFormat::Obj),
    };
    let input_format = args
        .input_format
        .as_deref()
        .map(InputFormat::parse)
        .transpose()?;
    let batch = Batch {
        inputs: args.inputs,
        input_format,
        output,
        format,
        config,
        engine: Engine::NarrowBand,
    };
    let mut progress = Console::new(batch.inputs.len(), args.verbose, args.quiet);
    let outcomes = batch.run(&mut progress)?;
    progress.finish();
    let failed: Vec<&FrameOutcome> = outcomes.iter().filter(|o| o.result.is_err()).collect();
    if failed.is_empty() {
        return Ok(ExitCode::SUCCESS);
    }
    eprintln!("{} of {} frames failed:", failed.len(), outcomes.len());
    for o in failed {
        if let Err(e) = &o.result {
            eprintln!("  {}: {e:#}", o.input.display());
        }
    }
    Ok(ExitCode::FAILURE)
}

/// A progress bar on a terminal, one plain line per frame elsewhere (farm logs).
struct Console {
    bar: Option<ProgressBar>,
    verbose: bool,
    quiet: bool,
}

impl Console {
    fn new(frames: usize, verbose: bool, quiet: bool) -> Console {
        let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
            let bar = ProgressBar::new(frames as u64);
            bar.set_style(
                ProgressStyle::with_template("{bar:40} {pos}/{len} frames {elapsed}<{eta} {msg}")
                    .expect("the template is valid"),
            );
            bar
        });
        Console {
            bar,
            verbose,
            quiet,
        }
    }

    fn say(&self, line: &str) {
        match &self.bar {
            Some(bar) => bar.println(line),
            None => eprintln!("{line}"),
        }
    }

    fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

impl Progress for Console {
    fn spacing_estimated(&mut self, from: &Path, spacing: f32) {
        if !self.quiet {
            self.say(&format!(
                "estimated particle spacing r = {spacing} from {} (from the local particle density); used for every frame",
                from.display()
            ));
        }
    }

    fn frame_done(&mut self, outcome: &FrameOutcome, done: usize, total: usize) {
        let name = outcome.input.display();
        match &outcome.result {
            Err(e) => self.say(&format!("[{done}/{total}] {name}: error: {e:#}")),
            Ok(stats) if !self.quiet => {
                let line = if self.verbose {
                    format!(
                        "[{done}/{total}] {name} -> {}: {stats}",
                        outcome.output.display()
                    )
                } else if stats.particles == 0 {
                    format!(
                        "[{done}/{total}] {name}: no particles, wrote an empty mesh to {}",
                        outcome.output.display()
                    )
                } else {
                    let t = stats.timings;
                    format!(
                        "[{done}/{total}] {name} -> {}: {} particles, {} triangles, {:.2} s",
                        outcome.output.display(),
                        stats.particles,
                        stats.triangles,
                        (t.read + t.reconstruction() + t.write).as_secs_f64()
                    )
                };
                self.say(&line);
            }
            Ok(_) => {}
        }
        if let Some(bar) = &self.bar {
            bar.set_position(done as u64);
        }
    }
}
