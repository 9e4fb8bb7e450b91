//! The `splash` command: parses arguments and hands the work to the library.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clap::{Args, Parser, Subcommand};

mod bench;
mod farm;
mod log;
mod memory;
#[cfg(test)]
mod options_table;
mod preview;

use splash_sph::frames::Output;
use splash_sph::pipeline::Batch;
use splash_sph::report::{Build, Report, ReportFormat};
use splash_sph::{Config, Overrides};

use farm::FarmArgs;
use log::{Console, LogFormat, RunArgs};
use memory::Metered;

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
    Recon(Box<Recon>),
    /// Isosurface of a particle quantity (pressure, density, speed, vorticity, λ2) per particle
    /// file, exact with respect to the SPH interpolant (Marching Correctors).
    Iso(Box<Iso>),
    /// Ray-trace a PNG of each frame's metaball surface, straight from the particles.
    Preview(Box<preview::PreviewArgs>),
    /// Inspect configurations.
    #[command(subcommand)]
    Config(ConfigCommand),
    /// Compare the engines on scenes at several cell sizes and thread counts; print the paper's
    /// Tables 1, 3/4 and 5/6 and write the raw records as JSON.
    Bench(bench::BenchArgs),
    /// Print a shell completion script, e.g. `splash completions bash >
    /// ~/.local/share/bash-completion/completions/splash`.
    Completions {
        /// bash, zsh, fish, elvish or powershell.
        shell: clap_complete::Shell,
    },
}

#[derive(Subcommand)]
enum ConfigCommand {
    /// Print the full configuration that the given file and flags resolve to, as TOML.
    Show(ConfigArgs),
}

/// The configuration of a run: built-in defaults, overridden by the config file, overridden by
/// these flags. Each flag is an option of `splash_sph::OPTIONS`: the first paragraph of its help
/// is the table's help text (the `options_table` test compares them), the rest this command
/// line's own.
#[derive(Args)]
struct ConfigArgs {
    /// TOML file with the reconstruction parameters (see configs/).
    #[arg(long)]
    config: Option<PathBuf>,

    /// Scalar field: ssp07, zb05, density, blobby, metaball or anisotropic, with its default
    /// parameters unless the configuration gives the same kind.
    ///
    /// Default: ssp07.
    #[arg(long)]
    field: Option<String>,

    /// Particle spacing r, the simulator's equilibrium distance between particles.
    ///
    /// Estimated from the first frame when neither this nor --particle-radius is given.
    #[arg(long, conflicts_with = "particle_radius")]
    spacing: Option<f32>,

    /// Particle radius as SPlisHSPlasH and splashsurf give it: r = 2 × radius.
    #[arg(long)]
    particle_radius: Option<f32>,

    /// Marching Cubes cell size: 2r, r, r/2, r/N, Kr or a length; at most 4r.
    ///
    /// Default: r/2. Larger cells than 4r lose the fluid's thin parts, then all of it.
    #[arg(long)]
    cell: Option<String>,

    /// Vertex normals: field (the field's gradient), grid (differences of the sampled grid:
    /// faster) or none.
    ///
    /// Default: field. Post-processed meshes (all but --raw) get area-weighted normals of the
    /// smoothed surface unless none.
    #[arg(long)]
    normals: Option<String>,

    /// Newton steps moving each vertex along its cube edge onto the field's exact isosurface
    /// (Marching Correctors); 0 keeps Marching Cubes' linear interpolation.
    ///
    /// Bare --correct: 3. Default: 0, vertices where Marching Cubes' linear interpolation
    /// puts them.
    #[arg(long, value_name = "N", num_args = 0..=1, require_equals = true, default_missing_value = "3")]
    correct: Option<u32>,

    /// Cubes per side of a block of the slices engine.
    ///
    /// Default: 64.
    #[arg(long)]
    block: Option<u32>,

    /// Reconstruction engine: narrow-band, full-gather, scatter or slices.
    ///
    /// Default: narrow-band. full-gather (Z-index gather on every grid vertex) and scatter
    /// (serial, SSP07 only) are the paper's baselines; slices is block-parallel Marching
    /// Slices, memory bounded per block (see --block). full-gather, scatter and slices give the
    /// same components; the narrow band too, except at small cells for blobs of a few cells
    /// farther than its 2r band from every surface particle (at cell r/2: 1 of 55 components
    /// on cbd-small frame 40).
    #[arg(long)]
    engine: Option<String>,

    /// Worker threads, all cores when not given; the mesh does not depend on it.
    #[arg(long)]
    threads: Option<usize>,

    /// Heap a frame may plan to use, e.g. 8G or 512M: every engine refuses a frame that needs
    /// more.
    ///
    /// Every engine estimates its need before its big allocations; the other frames go on.
    /// Default: 80 % of the smallest of the cgroup limit, SLURM's memory and the available
    /// memory.
    #[arg(long)]
    max_memory: Option<String>,

    /// Mesh format: obj, ply, ply-ascii, pov, vtk, vtu, vtp, usd or vdb; from the output's
    /// extension when not given, else obj.
    ///
    /// ply is binary little-endian; pov a POV-Ray mesh2 include (.inc); vtk legacy binary; vtu
    /// and vtp VTK XML, zlib-compressed; usd a .usda layer per frame, with the particles'
    /// velocities, and for a sequence a stage that plays them as one mesh (<name>.usda beside
    /// them); vdb an OpenVDB level set per frame (float grid `surface`, signed distance to the
    /// mesh within 3 voxels of the cell, negative inside; --attributes as grids, velocity as
    /// `v`).
    #[arg(long)]
    format: Option<String>,

    /// Rotate the mesh on output: z turns Y-up data Z-up, y turns Z-up data Y-up.
    ///
    /// Default: coordinates as they are.
    #[arg(long, value_name = "AXIS")]
    up_axis: Option<String>,

    /// Particle attributes interpolated onto the mesh's vertices, by name (velocity, density,
    /// …).
    ///
    /// Written to PLY, VTK, VTU, VTP and USD: v, vel and vx vy vz all find velocity; the value
    /// at a vertex is the kernel-weighted mean of the particles around it. For VDB, onto the
    /// level set's active voxels, a grid each.
    #[arg(long, value_name = "LIST")]
    attributes: Option<String>,

    /// Drop the particles outside this box (min x, min y, min z, max x, max y, max z) before
    /// reconstructing.
    ///
    /// Their count is logged.
    #[arg(
        long,
        value_name = "MINX,MINY,MINZ,MAXX,MAXY,MAXZ",
        allow_hyphen_values = true
    )]
    particle_aabb: Option<String>,

    /// Keep the field's exact isosurface: no smoothing and no volume restoration.
    ///
    /// By default the mesh is smoothed and each part given the volume of the particles inside
    /// it.
    #[arg(long)]
    raw: bool,

    /// In a sequence, average each frame's field and surface with its neighbouring frames'
    /// carried by the fluid's motion (experimental).
    ///
    /// The motion comes from particle ids, else velocities with post.frame_time: a low-pass in
    /// time against flicker, for about 1.9x the wall time.
    #[arg(long)]
    temporal: bool,

    /// Decimate with quadric edge collapses, keeping every vertex and triangle centre within
    /// this distance of the full surface.
    ///
    /// 0.1r (a tenth of the spacing) or a length. Closed and manifold, components and volume
    /// kept.
    #[arg(long, value_name = "LENGTH")]
    decimate: Option<String>,

    /// Drop the parts of the mesh enclosing less than this many particle volumes r³.
    ///
    /// After the default volume restoration a droplet of n particles holds n r³.
    #[arg(long, value_name = "V")]
    min_component: Option<f64>,

    /// Keep only the mesh inside this box (min x, min y, min z, max x, max y, max z); the cuts
    /// are capped, so it stays closed.
    #[arg(
        long,
        value_name = "MINX,MINY,MINZ,MAXX,MAXY,MAXZ",
        allow_hyphen_values = true
    )]
    mesh_aabb: Option<String>,

    /// What the volume restoration brings to N·r³: frame (the whole mesh, one offset) or
    /// component (each closed part to its own particles).
    ///
    /// Default: frame, which moves a frame's surface the way its neighbours' move: less
    /// flicker in a sequence, where a droplet's own target jumps with its particle count.
    #[arg(long, value_name = "SCOPE")]
    volume_scope: Option<String>,
}

impl ConfigArgs {
    fn resolve(&self) -> Result<Config> {
        let config = match &self.config {
            Some(path) => Config::from_file(path)?,
            None => Config::default(),
        };
        if self.threads == Some(0) {
            bail!("--threads must be at least 1");
        }
        let mut overrides = Overrides {
            field: self.field.clone(),
            spacing: self.particle_radius.map(|p| 2.0 * p).or(self.spacing),
            correct: self.correct,
            block: self.block,
            threads: self.threads,
            raw: self.raw.then_some(true),
            min_component: self.min_component,
            temporal: self.temporal.then_some(true),
            ..Overrides::default()
        };
        // The flags given as text, parsed by the library's one parser of each option.
        for (name, text) in [
            ("cell", &self.cell),
            ("normals", &self.normals),
            ("engine", &self.engine),
            ("max_memory", &self.max_memory),
            ("format", &self.format),
            ("up_axis", &self.up_axis),
            ("attributes", &self.attributes),
            ("particle_aabb", &self.particle_aabb),
            ("mesh_aabb", &self.mesh_aabb),
            ("decimate", &self.decimate),
            ("volume_scope", &self.volume_scope),
        ] {
            if let Some(text) = text {
                let flag = splash_sph::option(name).cli.name().unwrap_or(name);
                overrides
                    .set(name, text)
                    .with_context(|| format!("--{flag}"))?;
            }
        }
        Ok(config.apply(&overrides)?)
    }
}

#[derive(Args)]
#[command(after_help = "\
Inputs: PLY (ascii or binary; the vertex element's x, y, z), CSV (x, y, z columns by header name,
or the first three columns without a header), raw binary (.bin/.raw: little-endian f32 x y z
triples, nothing else), legacy VTK (.vtk), VTK XML (.vtu, .vtp), classic BGEO (.bgeo,
.bgeo.gz) and .xyz (f32 triples, or text). Every other per-particle value is an attribute
(--attributes). The format comes from the extension unless --input-format is given.

Lengths (--cell, band and support in the config) are multiples of the particle spacing r
(2r, r, r/2, r/4, 0.5r) or plain numbers in world units. The band of surface vertices spans 2r
around each surface particle (r for the density field), widened to r + cell when that is
larger (3r at cell 2r), and it grows by itself wherever the surface leaves it, so meshes are
closed at every cell size.

Sequences: a frame's number is the last run of digits in its file name; frames run in
number order. Exit status 0 only when every frame of the job has its mesh; a summary lists the
failed frames. Examples:
  splash recon 'sim/frame_*.ply' --cell r/2 -o 'mesh/fluid_{frame:04}.obj'
  splash recon sim/ --frames 100-400x2 --skip-existing -o mesh/
  SLURM_ARRAY_TASK_ID=3 splash recon sim/ --shard auto/16 -o mesh/")]
struct Recon {
    /// Particle files, directories of them, or quoted glob patterns ('sim/frame_*.ply').
    #[arg(required = true)]
    inputs: Vec<PathBuf>,

    /// Output: a directory (ending in /; frame numbers in names padded to 4 digits), a file
    /// for a single input, or a pattern with {stem} or {frame} / {frame:04}. Default:
    /// {stem}_surface.obj beside each input.
    #[arg(short, long)]
    output: Option<String>,

    #[command(flatten)]
    params: ConfigArgs,

    #[command(flatten)]
    farm: FarmArgs,

    #[command(flatten)]
    run: RunArgs,
}

#[derive(Args)]
#[command(after_help = "\
The quantity is A(x) = sum_j (m_j/rho_j) A_j W(x - x_j, 2h_j) with the cubic spline (support 2r
unless the file has an `h` column; volumes m/rho from mass and density columns when the file has
both, else from the particles as the density field computes them). The virtual grid's cell is
--cell (default r/2); the [iso] table of --config holds the kernel scale, Shepard
normalisation, trimming thresholds, seed reach and cache slices. -v prints the paper's figures:
seed cells, cells used, cache hit ratio, correction sizes and stage times. Examples:
  splash iso 'frames/*.ply' --attribute pressure --level 3000 --spacing 0.014 -o iso/
  splash iso frame.vtk --attribute velocity --magnitude --level 2.5 --attributes density -o v.ply
  splash iso frame.ply --attribute velocity --vorticity --level 20 -o w.ply
  splash iso frames/ --attribute velocity --lambda2 --level -50 -o vortices/")]
// recon's flags that shape the free surface mean nothing here: hidden, and refused if given.
#[command(
    mut_arg("correct", |a| a.help("Newton steps per vertex along its cube edge onto the \
        interpolant's level (--correct alone: 3, the default; --correct=0: plain Marching Cubes \
        vertices)")),
    mut_arg("field", |a| a.hide(true)),
    mut_arg("normals", |a| a.hide(true)),
    mut_arg("engine", |a| a.hide(true)),
    mut_arg("block", |a| a.hide(true)),
)]
struct Iso {
    #[command(flatten)]
    base: Recon,

    /// The particle attribute (any spelling of the alias table: pressure, density, v, …).
    #[arg(long, required = true)]
    attribute: String,

    /// The isovalue.
    #[arg(long, required = true, allow_hyphen_values = true)]
    level: f32,

    /// Isosurface of the magnitude of a vector attribute.
    #[arg(long, conflicts_with_all = ["vorticity", "lambda2"])]
    magnitude: bool,

    /// Isosurface of the vorticity magnitude |curl v| of a velocity attribute (SPH curl).
    #[arg(long, conflicts_with = "lambda2")]
    vorticity: bool,

    /// Isosurface of λ2, the middle eigenvalue of S² + Ω² of a velocity attribute's SPH
    /// gradient (Jeong & Hussain): vortex cores are where λ2 < 0, so take a negative --level
    /// (the paper's dam break: -150).
    #[arg(long)]
    lambda2: bool,

    /// Shepard-normalised interpolation (plain SPH by default, as in the paper).
    #[arg(long)]
    shepard: bool,

    /// Multiplies every particle's kernel support (the paper's 1, 0.75, 0.5).
    #[arg(long)]
    kernel_scale: Option<f32>,
}

fn main() -> ExitCode {
    memory::return_freed_memory();
    let args: Vec<std::ffi::OsString> = std::env::args_os().collect();
    // Known before clap runs, so that its usage errors are JSON lines too.
    let log_format = log::format_in_args(&args);
    let cli = match Cli::try_parse_from(&args) {
        Ok(cli) => cli,
        Err(e) if log_format == LogFormat::Json && e.use_stderr() => {
            let text = e.render().to_string();
            // clap's first paragraph says what is wrong; the usage and hints follow.
            let first = text.trim().split("\n\n").next().unwrap_or_default();
            let message = first.trim_start_matches("error: ");
            log::print_error(log_format, message);
            return ExitCode::from(2);
        }
        Err(e) => e.exit(),
    };
    let result = match cli.command {
        Command::Recon(args) => recon(*args, None),
        Command::Iso(args) => iso(*args),
        Command::Preview(args) => preview::preview(*args),
        Command::Bench(args) => bench::bench(args),
        Command::Config(ConfigCommand::Show(args)) => show_config(&args),
        Command::Completions { shell } => completions(shell),
    };
    result.unwrap_or_else(|e| {
        log::print_error(log_format, &format!("{e:#}"));
        ExitCode::FAILURE
    })
}

fn completions(shell: clap_complete::Shell) -> Result<ExitCode> {
    use clap::CommandFactory;
    use std::io::Write;
    // Into memory first: clap_complete panics on a failed write (a closed pipe).
    let mut script = Vec::new();
    clap_complete::generate(shell, &mut Cli::command(), "splash", &mut script);
    std::io::stdout()
        .write_all(&script)
        .context("writing the completion script")?;
    Ok(ExitCode::SUCCESS)
}

fn show_config(args: &ConfigArgs) -> Result<ExitCode> {
    let config = args.resolve()?;
    print!("{}", config.effective().to_toml());
    Ok(ExitCode::SUCCESS)
}

fn iso(mut args: Iso) -> Result<ExitCode> {
    let derived = match (args.magnitude, args.vorticity, args.lambda2) {
        (true, ..) => splash_sph::iso::Derived::Magnitude,
        (_, true, _) => splash_sph::iso::Derived::Vorticity,
        (.., true) => splash_sph::iso::Derived::Lambda2,
        _ => splash_sph::iso::Derived::Value,
    };
    let request = splash_sph::iso::IsoRequest {
        attribute: std::mem::take(&mut args.attribute),
        derived,
        level: args.level,
    };
    // recon's --correct (flattened in) sets iso's Newton steps here, not the Marching Cubes
    // field's.
    let correct = args.base.params.correct.take();
    let p = &args.base.params;
    for (given, flag) in [
        (p.field.is_some(), "--field"),
        (p.normals.is_some(), "--normals"),
        (p.engine.is_some(), "--engine"),
        (p.block.is_some(), "--block"),
    ] {
        if given {
            bail!("{flag} shapes recon's free surface and means nothing to iso");
        }
    }
    if args.base.run.report.is_some() {
        bail!(
            "--report is recon's and preview's: iso's figures (the paper's seed cells, cells \
             used, cache hit ratio, correction sizes, stage times) are in -v and in \
             --log-format json"
        );
    }
    let mut config = args.base.params.resolve()?;
    if let Some(n) = correct {
        config.iso.correct = n;
    }
    if args.shepard {
        config.iso.shepard = true;
    }
    if let Some(k) = args.kernel_scale {
        config.iso.kernel_scale = k;
    }
    config.validate()?;
    recon_with(args.base, config, Some(request))
}

fn recon(args: Recon, iso: Option<splash_sph::iso::IsoRequest>) -> Result<ExitCode> {
    let config = args.params.resolve()?;
    recon_with(args, config, iso)
}

fn recon_with(
    args: Recon,
    mut config: Config,
    iso: Option<splash_sph::iso::IsoRequest>,
) -> Result<ExitCode> {
    // The report gives the configuration as resolved, threads included.
    let report_config = args.run.report.is_some().then(|| config.clone());
    // Every frame runs on the workers asked for, as in Python (splash_sph::install).
    let threads = config.threads.take();
    let output = args
        .output
        .as_deref()
        .map_or(Output::BesideInput, Output::parse);
    let format = output.mesh_format(config.output.format)?;
    let input_format = args.run.input_format()?;
    let log_format = args.run.log_format()?;
    let shard = args.farm.shard()?;
    let mut console = Console::new(
        log_format,
        args.run.verbosity(),
        std::io::stderr().is_terminal(),
    );
    let inputs = args.farm.select(&args.inputs, &console)?;
    if let Some(path) = &args.run.report
        && ReportFormat::from_path(path).is_none()
    {
        bail!(
            "--report {}: a report ends in .json, .csv or .md",
            path.display()
        );
    }
    let batch = Batch {
        inputs,
        input_format,
        output,
        format,
        config,
        shard,
        skip_existing: args.farm.skip_existing,
        fail_fast: args.farm.fail_fast,
        iso,
    };
    // The report inside too: it gives the workers used.
    let report = splash_sph::install(threads, || -> Result<_> {
        let report = batch.run(&mut Metered(&mut console))?;
        if let (Some(path), Some(config)) = (&args.run.report, &report_config) {
            Report::of_run(&report.outcomes, config, this_build())?.write(path)?;
        }
        Ok(report)
    })??;
    Ok(if console.finish(&report) {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

/// This program, for the reports: its version, git revision (from build.rs), profile, and
/// whether the counting allocator measures the heap.
fn this_build() -> Build {
    Build {
        version: env!("CARGO_PKG_VERSION").into(),
        git_revision: option_env!("SPLASH_GIT_REVISION").map(str::to_string),
        profile: if cfg!(debug_assertions) {
            "debug"
        } else {
            "release"
        }
        .into(),
        heap_counted: memory::counting(),
    }
}

#[cfg(test)]
mod tests {
    use clap::CommandFactory;

    /// clap checks the definitions (unique names, valid defaults) only in debug builds, and the
    /// tests run in release: a duplicate `--correct` once went unnoticed this way.
    #[test]
    fn the_command_line_definitions_are_consistent() {
        super::Cli::command().debug_assert();
    }
}
