//! `splash preview`: one ray-traced PNG of the metaball surface per particle frame, without a
//! mesh. The frames, `--frames`, `--shard`, `--skip-existing`, the output names and the run are
//! recon's (the library's `frames` and `pipeline`), the logs, progress bar and summary too
//! (log.rs); a frame's work here is an image, and its figures are a renderer's.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result, anyhow, bail};
use clap::Args;
use splash_sph::preview::{
    BvhKind, Camera, Colouring, ImageRecord, PreviewStats, Previewer, Style, parse_colour,
    parse_size, robust_bounds, up_vector, write_png, write_report,
};
use splash_sph::{Bytes, Config, InputFormat, Vec3, estimate_spacing, read_particles};

use splash_sph::frames::{Output, output_paths};
use splash_sph::pipeline::{Plan, run_plan};

use crate::farm::FarmArgs;
use crate::log::{Console, FrameFigures, RunArgs, Verbosity};

#[derive(Args)]
#[command(after_help = "\
The surface is the metaball field's, the one `splash recon --field metaball` meshes (its
kernel, cut-off and iso level from the config's [field] table when that is a metaball field,
else the defaults), ray-traced through a Fitted BVH (Gourmel et al. 2010) with Blinn-Phong
shading: a key light from the camera's side (above-left of the viewer) with hard shadows, a fill
from the right and a sky ambient. --samples N averages N stratified rays per pixel, --ao adds
ambient occlusion, --color-by colours by an attribute (viridis, with a legend); every sample
is a hash of pixel and sample number, so the image does not depend on --threads or the run.
The config's [preview] table holds the same settings (samples, ao, color_by, legend).

Camera: without --camera, it frames the 0.5–99.5 % percentile box of the first frame of the
selected sequence (whatever the shard), seen from the front, right and above: direction
(0.45, 0.55, 1) from the box's centre for Y-up data, (0.45, -1, 0.55) with --up-axis z; --view
sets another direction. --camera without --look-at looks at that box's centre.

Examples:
  splash preview frames/*.ply --spacing 0.014 -o preview/ --size 1280x720
  splash preview frame_0040.ply --camera 0.6,0.5,2.2 --look-at 0.6,0.3,0.4 --fov 40 -o f40.png
  splash preview sim/ --frames 1-400x10 --shard auto/8 -o preview/
  splash preview frames/ --samples 4 --ao --color-by velocity -o png/")]
pub struct PreviewArgs {
    /// Particle files, directories of them, or quoted glob patterns ('sim/frame_*.ply').
    #[arg(required = true)]
    inputs: Vec<PathBuf>,

    /// Output: a directory (ending in /), a .png file for a single input, or a pattern with
    /// {stem} or {frame} / {frame:04}. Default: {stem}_preview.png beside each input.
    #[arg(short, long)]
    output: Option<String>,

    /// Image size WIDTHxHEIGHT in pixels (at most 16384 a side).
    #[arg(long, default_value = "1280x720")]
    size: String,

    /// Camera position X,Y,Z (default: framed automatically).
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    camera: Option<String>,

    /// The point the camera looks at, X,Y,Z (default: the centre of the fluid's box).
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    look_at: Option<String>,

    /// The image's up direction X,Y,Z (default: the data's up axis).
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    up: Option<String>,

    /// The data's up axis, y (SPlisHSPlasH, default) or z (Blender): the image's up
    /// direction and the auto camera's view.
    #[arg(long, value_name = "AXIS")]
    up_axis: Option<String>,

    /// Auto camera: direction from the fluid's centre towards the camera, X,Y,Z.
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    view: Option<String>,

    /// Vertical field of view in degrees.
    #[arg(long, default_value_t = 40.0)]
    fov: f32,

    /// Background colour, #rrggbb or R,G,B.
    #[arg(long, default_value = "#eceef2")]
    background: String,

    /// Fluid colour, #rrggbb or R,G,B.
    #[arg(long, default_value = "#3a7bd5")]
    colour: String,

    /// No shadow rays.
    #[arg(long)]
    no_shadows: bool,

    /// Rays per pixel, stratified and deterministic (default: the config's [preview] samples, 1).
    #[arg(long, value_name = "N")]
    samples: Option<u32>,

    /// Ambient occlusion with N hemisphere rays per pixel (8 when N is left out; default: the
    /// config's [preview] ao, 0 = off).
    #[arg(long, value_name = "N", num_args = 0..=1, default_missing_value = "8")]
    ao: Option<u32>,

    /// Colour the surface by a particle attribute through viridis (a vector by its magnitude,
    /// e.g. velocity → |v|), with a legend of its minimum and maximum.
    #[arg(long, value_name = "ATTRIBUTE")]
    color_by: Option<String>,

    /// No colour scale in images coloured by an attribute.
    #[arg(long)]
    no_legend: bool,

    /// Acceleration structure: fitted (the paper's FBVH, default) or plain (its Sec. 4 BVH,
    /// to compare).
    #[arg(long, default_value = "fitted")]
    bvh: String,

    /// TOML file with the parameters (spacing, [field], threads, max_memory).
    #[arg(long)]
    config: Option<PathBuf>,

    /// Particle spacing r. Estimated from the first frame when neither this nor
    /// --particle-radius is given.
    #[arg(long, conflicts_with = "particle_radius")]
    spacing: Option<f32>,

    /// Particle radius as SPlisHSPlasH gives it: r = 2 × radius.
    #[arg(long)]
    particle_radius: Option<f32>,

    /// Worker threads (default: all cores). The image does not depend on it.
    #[arg(long)]
    threads: Option<usize>,

    /// Memory the hierarchy and image may take, e.g. 8G (default: 80 % of what is available).
    #[arg(long)]
    max_memory: Option<String>,

    #[command(flatten)]
    farm: FarmArgs,

    #[command(flatten)]
    run: RunArgs,
}

fn vector(text: &str, flag: &str) -> Result<Vec3> {
    let parts: Vec<f32> = text
        .split(',')
        .map(|p| p.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| anyhow!("--{flag} {text}: expected three numbers X,Y,Z"))?;
    match parts[..] {
        [x, y, z] if x.is_finite() && y.is_finite() && z.is_finite() => Ok(Vec3::new(x, y, z)),
        [_, _, _] => bail!("--{flag} {text}: the coordinates must be finite"),
        _ => bail!("--{flag} {text}: expected three numbers X,Y,Z"),
    }
}

impl PreviewArgs {
    fn config(&self) -> Result<Config> {
        let mut config = match &self.config {
            Some(path) => Config::from_file(path)?,
            None => Config::default(),
        };
        if let Some(r) = self.spacing {
            config.spacing = Some(r);
        }
        if let Some(p) = self.particle_radius {
            config.spacing = Some(2.0 * p);
        }
        if let Some(n) = self.threads {
            if n == 0 {
                bail!("--threads must be at least 1");
            }
            config.threads = Some(n);
        }
        if let Some(m) = &self.max_memory {
            config.max_memory = Some(Bytes::parse(m).context("--max-memory")?);
        }
        if let Some(n) = self.samples {
            config.preview.samples = n;
        }
        if let Some(n) = self.ao {
            config.preview.ao = n;
        }
        if let Some(a) = &self.color_by {
            config.preview.color_by = Some(a.clone());
        }
        if self.no_legend {
            config.preview.legend = false;
        }
        config.validate()?;
        Ok(config)
    }
}

/// How the camera is chosen.
struct CameraPlan {
    width: u32,
    height: u32,
    fov: f32,
    up: Vec3,
    position: Option<Vec3>,
    look_at: Option<Vec3>,
    view: Option<Vec3>,
}

impl CameraPlan {
    fn needs_frame(&self) -> bool {
        self.position.is_none() || self.look_at.is_none()
    }

    fn camera(&self, reference: Option<&[Vec3]>, margin: f32) -> Result<Camera> {
        let (w, h, fov, up) = (self.width, self.height, self.fov, self.up);
        Ok(match (self.position, self.look_at, reference) {
            (Some(p), Some(t), _) => Camera::look_at(p, t, up, fov, w, h)?,
            (Some(p), None, Some(points)) => {
                let (lo, hi) = robust_bounds(points);
                Camera::look_at(p, 0.5 * (lo + hi), up, fov, w, h)?
            }
            (None, _, Some(points)) => Camera::auto(points, margin, up, self.view, fov, w, h)?,
            (_, _, None) => bail!(
                "no frame of the sequence has particles to frame the camera on: give --camera \
                 and --look-at"
            ),
        })
    }
}

pub fn preview(args: PreviewArgs) -> Result<ExitCode> {
    let mut config = args.config()?;
    // The previewer runs on the workers asked for, as recon's frames do.
    let threads = config.threads.take();
    let camera_plan = args.camera_plan()?;
    let style = Style {
        background: parse_colour(&args.background).context("--background")?,
        colour: parse_colour(&args.colour).context("--colour")?,
        shadows: !args.no_shadows,
        samples: config.preview.samples,
        ao: config.preview.ao,
        legend: config.preview.legend,
    };
    let color_by = config.preview.color_by.clone();
    let bvh = BvhKind::parse(&args.bvh).context("--bvh")?;
    let input_format = args.run.input_format()?;
    let log_format = args.run.log_format()?;
    let shard = args.farm.shard()?;
    let output = args.output()?;
    if let Some(path) = &args.run.report
        && path.extension().is_none_or(|e| e != "json")
    {
        bail!(
            "--report {}: the preview report is a .json file",
            path.display()
        );
    }

    let mut console = Console::new(
        log_format,
        args.run.verbosity(),
        std::io::stderr().is_terminal(),
    );
    // The frames, output names and job share follow recon's rules.
    let inputs = args.farm.select(&args.inputs, &console)?;
    let outputs = output_paths(&inputs, &output, "preview", "_preview", "png")?;
    let job = Plan::new(&inputs, &outputs, shard, args.farm.skip_existing);
    job.check_writable()?;
    console.start(&job);

    let report = splash_sph::install(threads, || -> Result<_> {
        let (previewer, camera) = setup(
            &inputs,
            input_format,
            &mut config,
            &camera_plan,
            bvh,
            &console,
        )?;
        let report = run_plan(
            job,
            args.farm.fail_fast,
            &mut console,
            |input, output, _| {
                let start = Instant::now();
                let mut particles = read_particles(input, input_format)?;
                let colouring = color_by
                    .as_deref()
                    .map(|name| Colouring::from_frame(input, &mut particles.attributes, name))
                    .transpose()?;
                let preview = previewer.render_coloured(
                    &particles.positions,
                    colouring.as_ref(),
                    &camera,
                    &style,
                )?;
                write_png(output, &preview.image)?;
                Ok(PreviewFrame {
                    stats: preview.stats,
                    kind: bvh,
                    seconds: start.elapsed().as_secs_f64(),
                })
            },
        );
        // The report inside too: it gives the workers used.
        if let Some(path) = &args.run.report {
            let size = [camera_plan.width, camera_plan.height];
            let images = report.outcomes.iter().filter_map(|o| {
                let frame = o.result.as_ref().ok()?;
                Some(ImageRecord {
                    input: &o.input,
                    output: &o.output,
                    stats: &frame.stats,
                    seconds: frame.seconds,
                })
            });
            write_report(path, images, bvh, size, config.spacing)?;
        }
        Ok(report)
    })??;
    Ok(if console.finish(&report) {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

impl PreviewArgs {
    /// The camera asked for: size, field of view, up direction, and position, target or view
    /// where given.
    fn camera_plan(&self) -> Result<CameraPlan> {
        let (width, height) = parse_size(&self.size).context("--size")?;
        let z_up = match self
            .up_axis
            .as_deref()
            .map(|a| a.trim().to_ascii_lowercase())
        {
            None => false,
            Some(a) if a == "y" => false,
            Some(a) if a == "z" => true,
            Some(a) => bail!("--up-axis {a}: expected y or z"),
        };
        let optional = |text: &Option<String>, flag| text.as_deref().map(|c| vector(c, flag));
        let plan = CameraPlan {
            width,
            height,
            fov: self.fov,
            up: match &self.up {
                Some(u) => vector(u, "up")?,
                None => up_vector(z_up),
            },
            position: optional(&self.camera, "camera").transpose()?,
            look_at: optional(&self.look_at, "look-at").transpose()?,
            view: optional(&self.view, "view").transpose()?,
        };
        if plan.look_at.is_some() && plan.position.is_none() {
            bail!("--look-at needs --camera (without both, the camera is framed automatically)");
        }
        if !(self.fov > 0.0 && self.fov < 180.0) {
            bail!(
                "--fov {}: the field of view must lie strictly between 0 and 180 degrees",
                self.fov
            );
        }
        Ok(plan)
    }

    /// `-o`, which must name PNG files.
    fn output(&self) -> Result<Output> {
        let output = self
            .output
            .as_deref()
            .map_or(Output::BesideInput, Output::parse);
        if let Some(ext) = output
            .extension()
            .filter(|e| !e.eq_ignore_ascii_case("png"))
        {
            bail!("preview writes PNG images: the output name's .{ext} extension should be .png");
        }
        Ok(output)
    }
}

/// The previewer and the camera of the whole run. The spacing and the auto camera come from
/// the first readable frame of the whole selection, so that every shard and restart draws the
/// same surface from the same view.
fn setup(
    inputs: &[PathBuf],
    input_format: Option<InputFormat>,
    config: &mut Config,
    plan: &CameraPlan,
    bvh: BvhKind,
    console: &Console,
) -> Result<(Previewer, Camera)> {
    let needs_reference = config.spacing.is_none() || plan.needs_frame();
    let reference = if needs_reference {
        inputs.iter().find_map(|input| {
            let p = read_particles(input, input_format).ok()?;
            (!p.is_empty()).then_some((input, p.positions))
        })
    } else {
        None
    };
    if config.spacing.is_none() {
        let (input, points) = reference.as_ref().ok_or_else(|| {
            anyhow!("no frame has particles to estimate the spacing from: give --spacing")
        })?;
        let r = estimate_spacing(points).ok_or_else(|| {
            anyhow!(
                "cannot estimate the particle spacing from {}: give --spacing",
                input.display()
            )
        })?;
        console.spacing(input, r);
        config.spacing = Some(r);
    }
    let previewer = Previewer::new(config)?.with_bvh(bvh);
    let camera = plan.camera(
        reference.as_ref().map(|(_, p)| p.as_slice()),
        previewer.margin(),
    )?;
    Ok((previewer, camera))
}

/// The `--report` file: the run's settings and every written frame's figures.
/// One image's figures, as the log and the report give them.
pub struct PreviewFrame {
    stats: PreviewStats,
    kind: BvhKind,
    /// Reading, building, rendering and writing.
    seconds: f64,
}

impl FrameFigures for PreviewFrame {
    fn particles(&self) -> usize {
        self.stats.particles
    }

    fn seconds(&self) -> f64 {
        self.seconds
    }

    fn line(&self, output: &Path, verbosity: Verbosity) -> String {
        let s = &self.stats;
        let line = format!(
            " -> {}: {} particles, build {:.0} ms, render {:.0} ms, {:.2} Mrays/s, {:.2} s",
            output.display(),
            s.particles,
            s.build.as_secs_f64() * 1e3,
            s.render.as_secs_f64() * 1e3,
            s.rays_per_second() / 1e6,
            self.seconds
        );
        match verbosity {
            Verbosity::Verbose => format!("{line}\n  {}", figures(s, self.kind)),
            _ => line,
        }
    }

    fn json(&self) -> serde_json::Map<String, serde_json::Value> {
        let s = &self.stats;
        let mut fields = serde_json::Map::new();
        fields.insert("build_ms".into(), millis(s.build).into());
        fields.insert("render_ms".into(), millis(s.render).into());
        fields.insert("rays_per_second".into(), s.rays_per_second().round().into());
        fields.insert("hits".into(), s.hits.into());
        fields
    }
}

fn millis(d: std::time::Duration) -> f64 {
    (d.as_secs_f64() * 1e6).round() / 1e3
}

fn figures(s: &PreviewStats, kind: BvhKind) -> String {
    let rays = s.rays.rays.max(1) as f64;
    format!(
        "{} BVH: {} nodes, {} leaves, {:.1} metaballs per leaf, depth {}, {:.1} MB; {} rays ({} camera, {} hits); per ray: {:.2} node traversals, {:.2} intersection tests, {:.1} metaballs considered ({:.1} within R of the ray)",
        kind.name(),
        s.bvh.nodes,
        s.bvh.leaves,
        s.bvh.per_leaf(),
        s.bvh.depth,
        s.bvh.bytes as f64 / 1e6,
        s.rays.rays,
        s.camera_rays,
        s.hits,
        s.rays.nodes as f64 / rays,
        s.rays.leaves as f64 / rays,
        s.rays.metaballs as f64 / rays,
        s.rays.along_ray as f64 / rays,
    )
}
