//! `splash bench temporal`: the jitter of whole sequences (issue 38). Consecutive frames are
//! reconstructed with the raw isosurface, the default post-processing, the user's own variants
//! and, when splashsurf is on the PATH, the peer's recommended pipeline; each sequence of
//! meshes is measured against the fluid's own motion ([`splash_sph::temporal::jitter`]), with
//! its wall time, peak memory and render figures.

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::Args;

use splash_sph::frames::{Output, select};
use splash_sph::io::read_mesh;
use splash_sph::mesh::{quality, volume_error};
use splash_sph::pipeline::{Batch, FrameOutcome, Progress};
use splash_sph::temporal::{DROPLET, FrameMotion, Jitter, PARTS, Window, frame_jitter};
use splash_sph::{Config, Length, MeshFormat, TriMesh, Vec3, estimate_spacing, read_particles};

use super::rigid;
use crate::memory::HeapScope;

#[derive(Args)]
#[command(after_help = "\
PARTICLES are consecutive frames of one simulation (every output step: a sparser sequence
mixes motion into the jitter). Each mesh sequence is measured on its inner frames t: for every
vertex x with outward normal n, d± = signed distance to mesh t±1, m± = n · the fluid's
displacement around x towards frame t±1 (cubic-spline mean over 2r of the particles matched by
their ids, else velocity x --frame-time), e+ = d+ + m+, e- = d- - m-. jitter = RMS((e+ + e-)/2)
/ r: surface motion the fluid does not explain (a surface moving with the particles scores 0);
carried = RMS((c+ + c-)/2) / r with c± the signed distance to mesh t±1 at x + the
displacement towards it: bumps the flow carries along the surface cancel there even when the
frame intervals differ; e+ RMS adds smooth drift; surface = RMS((d+ + d-)/2) / r ignores the
particles. Vertices more than 2r from a neighbouring mesh are left out (the column says how
many). A second table splits the carried figure by part: the body (the component of largest
volume), pieces, and droplets enclosing less than 10 r³, whose few particles rearrange as they
fly.
Variants: raw (--raw), single-frame (each frame post-processed alone, the default), temporal
(--temporal: surfaces that follow the fluid), every --variant NAME=FILE.toml
(a configuration file laid over the given one), every --meshes NAME=DIR (meshes already
written, named like the frames: DIR/<frame stem>[_surface].ply|obj|vtk|vtu|vtp), and peer (splashsurf's
recommended pipeline: density field, support 2r, iso 0.6, weighted smoothing 25, cleanup,
normal smoothing 10) when splashsurf is on the PATH or --peer names it.
--rigid-step X,Y,Z measures the first frame moved rigidly by X,Y,Z cells a frame instead: the
field moves exactly with the particles, so each row reads the share of its jitter that comes
from the grid the surface moves across (whole cells read 0).
Example:
  splash bench temporal ../shared/data/dense-dambreak --spacing 0.04 --threads 2")]
pub struct BenchTemporalArgs {
    /// Particle frames: a directory, files or a pattern.
    #[arg(required = true)]
    inputs: Vec<PathBuf>,

    /// Particle spacing r; estimated from the first frame when absent.
    #[arg(long)]
    spacing: Option<f32>,

    /// Particle radius, as SPlisHSPlasH and splashsurf give it: r = 2 × radius.
    #[arg(long, conflicts_with = "spacing")]
    particle_radius: Option<f32>,

    /// Frames to use (a frame set: 1-100, 1-100x2, 3,5,7).
    #[arg(long)]
    frames: Option<String>,

    /// Cell size of every splash variant (default: the configuration's, r/2).
    #[arg(long)]
    cell: Option<String>,

    /// Worker threads of every run (default: all cores).
    #[arg(long)]
    threads: Option<usize>,

    /// TOML configuration every splash variant starts from.
    #[arg(long)]
    config: Option<PathBuf>,

    /// Another splash variant: NAME=FILE.toml, laid over --config (repeat).
    #[arg(long, value_name = "NAME=FILE")]
    variant: Vec<String>,

    /// Meshes already written to measure too: NAME=DIR (repeat).
    #[arg(long, value_name = "NAME=DIR")]
    meshes: Vec<String>,

    /// Seconds between frames, to carry particles by velocity when the files have no ids.
    #[arg(long)]
    frame_time: Option<f32>,

    /// The splashsurf binary for the peer's row (default: splashsurf on the PATH); "none"
    /// leaves the row out.
    #[arg(long)]
    peer: Option<String>,

    /// Keep every variant's meshes in DIR/NAME/ (default: a temporary directory, removed).
    #[arg(long)]
    keep: Option<PathBuf>,

    /// Measure the first frame translated rigidly by X,Y,Z cells a frame instead of the
    /// frames themselves: what is left is the grid's share of the jitter.
    #[arg(long, value_name = "X,Y,Z", value_parser = rigid::parse_step)]
    rigid_step: Option<Vec3>,

    /// How many frames --rigid-step makes.
    #[arg(long, default_value_t = 8, requires = "rigid_step")]
    rigid_frames: usize,
}

/// A sequence of meshes to measure, and how it was made.
struct Variant {
    name: String,
    dir: PathBuf,
    /// Wall seconds and peak memory (heap for splash, resident set for the peer) of the run
    /// that made it; None for meshes given.
    cost: Option<(f64, u64)>,
}

pub fn run(args: BenchTemporalArgs) -> Result<ExitCode> {
    let selection = select(&args.inputs, args.frames.as_deref())?;
    let mut frames = selection.files;
    let wanted = if args.rigid_step.is_some() {
        args.rigid_frames
    } else {
        frames.len()
    };
    if wanted < 3 {
        bail!("jitter needs at least 3 consecutive frames; {wanted} selected");
    }
    let mut base = match &args.config {
        Some(path) => Config::from_file(path)?,
        None => Config::default(),
    };
    let spacing = match (args.spacing, args.particle_radius, base.spacing) {
        (Some(r), _, _) => r,
        (_, Some(p), _) => 2.0 * p,
        (_, _, Some(r)) => r,
        _ => {
            let first = read_particles(&frames[0], None)?;
            estimate_spacing(&first.positions).with_context(|| {
                format!("cannot estimate the spacing from '{}'", frames[0].display())
            })?
        }
    };
    base.spacing = Some(spacing);
    if let Some(cell) = &args.cell {
        base.cell = Length::parse(cell).context("--cell")?;
    }
    base.threads = args.threads;
    base.validate()?;

    let temp;
    let root = match &args.keep {
        Some(dir) => dir.clone(),
        None => {
            temp = TempDir::new()?;
            temp.0.clone()
        }
    };
    // What the table's heading says the frames are.
    let source = match args.rigid_step {
        Some(step) => format!(
            "{} moved rigidly by {step} cells a frame",
            frames[0].display()
        ),
        None => frames[0]
            .parent()
            .unwrap_or(Path::new("."))
            .display()
            .to_string(),
    };
    if let Some(step) = args.rigid_step {
        let cell = base.cell.resolve(spacing);
        eprintln!("{source}: {} frames", args.rigid_frames);
        frames = rigid::write_frames(
            &frames[0],
            step * cell,
            args.rigid_frames,
            &root.join("rigid"),
        )?;
    }
    let mut runs: Vec<(String, Config)> = Vec::new();
    let mut raw = base.clone();
    raw.post.raw = true;
    runs.push(("raw".into(), raw));
    let mut single = base.clone();
    single.post.temporal = false;
    runs.push(("single-frame".into(), single));
    let mut temporal = base.clone();
    temporal.post.temporal = true;
    runs.push(("temporal".into(), temporal));
    for v in &args.variant {
        let (name, file) = split_named(v, "--variant")?;
        let text = std::fs::read_to_string(file).with_context(|| format!("--variant {v}"))?;
        let mut merged: toml::Table = toml::from_str(&base.to_toml())?;
        let over: toml::Table = toml::from_str(&text).with_context(|| format!("--variant {v}"))?;
        lay_over(&mut merged, over);
        let config = Config::from_toml(&toml::to_string(&merged)?)
            .with_context(|| format!("--variant {v}"))?;
        runs.push((name.to_string(), config));
    }
    let mut variants = Vec::new();
    for (name, config) in runs {
        let dir = root.join(&name);
        eprintln!("{name}: reconstructing {} frames", frames.len());
        let cost = run_splash(&frames, &dir, config)?;
        variants.push(Variant {
            name,
            dir,
            cost: Some(cost),
        });
    }
    let peer = match args.peer.as_deref() {
        Some("none") => None,
        Some(bin) => Some(PathBuf::from(bin)),
        None => on_path("splashsurf"),
    };
    if let Some(peer) = peer {
        let dir = root.join("peer");
        eprintln!(
            "peer: {} reconstructing {} frames",
            peer.display(),
            frames.len()
        );
        let cost = run_peer(&peer, &frames, &dir, spacing, base.cell, args.threads)?;
        variants.push(Variant {
            name: "peer".into(),
            dir,
            cost: Some(cost),
        });
    }
    for m in &args.meshes {
        let (name, dir) = split_named(m, "--meshes")?;
        variants.push(Variant {
            name: name.into(),
            dir: dir.into(),
            cost: None,
        });
    }

    eprintln!("measuring");
    let table = measure(&frames, &variants, spacing, args.frame_time)?;
    println!(
        "{} frames ({} inner) of {}, r = {spacing}, cell {}, {} threads",
        frames.len(),
        frames.len() - 2,
        source,
        base.cell,
        args.threads.map_or_else(|| "all".into(), |t| t.to_string())
    );
    println!(
        "| mesh | jitter r | carried r | e+ RMS r | surface r | left out | triangles | volume err max | bumpiness ° | slivers % | crossing faces (frames) | wall s | peak MiB |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for (v, row) in variants.iter().zip(&table) {
        let (wall, peak) = match v.cost {
            Some((s, bytes)) => (
                format!("{s:.2}"),
                format!("{:.0}", bytes as f64 / 1048576.0),
            ),
            None => ("–".into(), "–".into()),
        };
        let j = &row.jitter;
        println!(
            "| {} | {:.4} | {:.4} | {:.4} | {:.4} | {:.2} % | {:.0} | {:+.2} % | {:.2} | {:.2} | {} ({}) | {wall} | {peak} |",
            v.name,
            j.rms(),
            j.carried_rms(),
            j.forward_rms(),
            j.surface_rms(),
            100.0 * j.left_out as f64 / (j.vertices + j.left_out).max(1) as f64,
            row.triangles,
            100.0 * row.worst_volume,
            row.bumpiness,
            100.0 * row.slivers,
            row.crossing_faces,
            row.crossing_frames,
        );
    }
    println!(
        "\nCarried jitter by part, r (share of the carried vertices): the body is the component \
         of largest volume, droplets enclose less than {DROPLET} r³, pieces the rest"
    );
    println!("| mesh | {} |", PARTS.join(" | "));
    println!("|---|{}", "---|".repeat(PARTS.len()));
    for (v, row) in variants.iter().zip(&table) {
        let j = &row.jitter;
        let cells: Vec<String> = j
            .parts
            .iter()
            .map(|p| {
                if p.vertices == 0 {
                    return "–".to_string();
                }
                let share = 100.0 * p.vertices as f64 / j.carried_vertices as f64;
                format!("{:.4} ({share:.1} %)", p.rms())
            })
            .collect();
        println!("| {} | {} |", v.name, cells.join(" | "));
    }
    Ok(ExitCode::SUCCESS)
}

/// A variant's figures over the sequence.
struct Row {
    jitter: Jitter,
    /// Means per frame.
    triangles: f64,
    bumpiness: f64,
    slivers: f64,
    /// The volume error farthest from 0, against N·r³.
    worst_volume: f64,
    /// Faces that cross another face of the same mesh (the exact test), and the frames with
    /// any.
    crossing_faces: usize,
    crossing_frames: usize,
}

/// Measures every variant on the inner frames, three frames of particles and meshes at a time.
fn measure(
    frames: &[PathBuf],
    variants: &[Variant],
    spacing: f32,
    frame_time: Option<f32>,
) -> Result<Vec<Row>> {
    let mut rows: Vec<Row> = variants
        .iter()
        .map(|_| Row {
            jitter: Jitter::default(),
            triangles: 0.0,
            bumpiness: 0.0,
            slivers: 0.0,
            worst_volume: 0.0,
            crossing_faces: 0,
            crossing_frames: 0,
        })
        .collect();
    let load = |path: &Path| -> Result<FrameMotion> {
        let p = read_particles(path, None)?;
        let mut attributes = p.attributes;
        let (motion, why) = FrameMotion::new(p.positions, &mut attributes);
        if let Some(why) = why {
            eprintln!("warning: '{}': {why}; using velocities", path.display());
        }
        Ok(motion)
    };
    let mut window: Vec<FrameMotion> = vec![load(&frames[0])?, load(&frames[1])?];
    let mut meshes: Vec<Vec<TriMesh>> = Vec::new();
    for v in variants {
        meshes.push(vec![mesh_of(v, &frames[0])?, mesh_of(v, &frames[1])?]);
    }
    for (k, frame) in frames.iter().enumerate() {
        // Render figures of every frame, jitter of the inner ones.
        if k >= 2 {
            window.push(load(frame)?);
            for (v, m) in variants.iter().zip(&mut meshes) {
                m.push(mesh_of(v, frame)?);
            }
        }
        let at = k.min(2);
        let particles = window[at].positions.len();
        for (row, m) in rows.iter_mut().zip(&meshes) {
            let q = quality(&m[at]);
            row.triangles += q.faces as f64;
            row.bumpiness += q.bumpiness;
            row.slivers += q.slivers;
            row.crossing_faces += q.self_intersecting_faces;
            row.crossing_frames += usize::from(q.self_intersecting_faces > 0);
            let e = volume_error(q.volume, particles, spacing);
            if e.abs() > row.worst_volume.abs() {
                row.worst_volume = e;
            }
        }
        if k >= 2 {
            let [before, now, after] = [&window[0], &window[1], &window[2]];
            // Each particle of frame t: its displacement to t+1, and since t−1.
            let forward = now.displacements(after, 1, frame_time);
            let backward = now.displacements(before, -1, frame_time);
            let (Some(forward), Some(backward)) = (forward, backward) else {
                bail!(
                    "'{}' and its neighbours have neither particle ids nor velocities with \
                     --frame-time: the fluid's motion is unknown",
                    frames[k - 1].display()
                );
            };
            let backward: Vec<_> = backward.into_iter().map(|d| d.map(|d| -d)).collect();
            for (row, m) in rows.iter_mut().zip(&meshes) {
                let w = Window {
                    meshes: [&m[0], &m[1], &m[2]],
                    particles: now,
                    forward: &forward,
                    backward: &backward,
                };
                row.jitter += frame_jitter(&w, spacing)?;
            }
            window.remove(0);
            for m in &mut meshes {
                m.remove(0);
            }
        }
    }
    for row in &mut rows {
        let n = frames.len() as f64;
        row.triangles /= n;
        row.bumpiness /= n;
        row.slivers /= n;
    }
    Ok(rows)
}

/// Variant `v`'s mesh of `frame`: DIR/<stem>.<any mesh extension splash reads>.
fn mesh_of(v: &Variant, frame: &Path) -> Result<TriMesh> {
    let stem = frame
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or_default();
    let stem = stem.strip_suffix(".bgeo").unwrap_or(stem);
    for suffix in ["", "_surface"] {
        for ext in ["ply", "obj", "vtk", "vtu", "vtp"] {
            let path = v.dir.join(format!("{stem}{suffix}.{ext}"));
            if path.is_file() {
                return Ok(read_mesh(&path)?.mesh);
            }
        }
    }
    bail!(
        "{}: no mesh of '{}' in '{}'",
        v.name,
        frame.display(),
        v.dir.display()
    )
}

/// Runs the sequence as `splash recon` does, into `dir` as binary PLY: wall seconds and peak
/// heap bytes.
fn run_splash(frames: &[PathBuf], dir: &Path, config: Config) -> Result<(f64, u64)> {
    struct Quiet(usize);
    impl Progress for Quiet {
        fn frame_done(&mut self, o: &FrameOutcome, _: usize, _: usize) {
            if let Err(e) = &o.result {
                eprintln!("error: {e}");
                self.0 += 1;
            }
        }
    }
    let batch = Batch {
        inputs: frames.to_vec(),
        input_format: None,
        output: Output::Directory(dir.to_path_buf()),
        format: MeshFormat::PlyBinary,
        config,
        shard: None,
        skip_existing: false,
        fail_fast: true,
        iso: None,
    };
    let heap = HeapScope::start();
    let start = Instant::now();
    let mut quiet = Quiet(0);
    let report = batch.run(&mut quiet)?;
    let wall = start.elapsed().as_secs_f64();
    if !report.complete() {
        bail!("{} frames failed", quiet.0.max(1));
    }
    Ok((wall, heap.peak() as u64))
}

/// Runs splashsurf's recommended pipeline frame by frame into `dir`: wall seconds and the
/// largest resident set of its processes.
fn run_peer(
    peer: &Path,
    frames: &[PathBuf],
    dir: &Path,
    spacing: f32,
    cell: Length,
    threads: Option<usize>,
) -> Result<(f64, u64)> {
    std::fs::create_dir_all(dir)?;
    // splashsurf's lengths are multiples of its particle radius, r/2.
    let cube = cell.resolve(spacing) / (spacing / 2.0);
    let start = Instant::now();
    for frame in frames {
        let stem = frame
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("frame");
        let mut cmd = Command::new(peer);
        cmd.arg("reconstruct").arg(frame);
        cmd.args([
            "-r",
            &(spacing / 2.0).to_string(),
            "-l",
            "2.0",
            "-c",
            &cube.to_string(),
        ]);
        cmd.args(["-t", "0.6", "--normals=on", "--mesh-smoothing-weights=on"]);
        cmd.args([
            "--mesh-smoothing-iters=25",
            "--mesh-cleanup=on",
            "--normals-smoothing-iters=10",
            "-q",
        ]);
        if let Some(n) = threads {
            cmd.args(["-n", &n.to_string()]);
        }
        cmd.arg("-o").arg(dir.join(format!("{stem}.ply")));
        let out = cmd
            .output()
            .with_context(|| format!("running {}", peer.display()))?;
        if !out.status.success() {
            bail!(
                "{} failed on '{}': {}",
                peer.display(),
                frame.display(),
                String::from_utf8_lossy(&out.stderr).trim()
            );
        }
    }
    let wall = start.elapsed().as_secs_f64();
    Ok((wall, children_peak_rss()))
}

/// The largest resident set of the waited-for children, in bytes.
fn children_peak_rss() -> u64 {
    // SAFETY: getrusage fills the struct it is given.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    if unsafe { libc::getrusage(libc::RUSAGE_CHILDREN, &mut usage) } != 0 {
        return 0;
    }
    usage.ru_maxrss as u64 * 1024
}

fn on_path(name: &str) -> Option<PathBuf> {
    std::env::split_paths(&std::env::var_os("PATH")?)
        .map(|d| d.join(name))
        .find(|p| p.is_file())
}

fn split_named<'a>(text: &'a str, flag: &str) -> Result<(&'a str, &'a str)> {
    match text.split_once('=') {
        Some((name, value)) if !name.is_empty() && !value.is_empty() => Ok((name, value)),
        _ => bail!("{flag} {text}: expected NAME=PATH"),
    }
}

/// `over`'s keys replace `base`'s, tables merged key by key.
fn lay_over(base: &mut toml::Table, over: toml::Table) {
    for (key, value) in over {
        match (base.get_mut(&key), value) {
            (Some(toml::Value::Table(b)), toml::Value::Table(o)) => lay_over(b, o),
            (_, value) => {
                base.insert(key, value);
            }
        }
    }
}

/// A directory removed when dropped.
struct TempDir(PathBuf);

impl TempDir {
    fn new() -> Result<TempDir> {
        let dir =
            std::env::temp_dir().join(format!("splash-bench-temporal-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir)?;
        Ok(TempDir(dir))
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}
