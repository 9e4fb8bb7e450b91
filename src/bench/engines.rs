//! `splash bench`: the paper's comparison matrix on the user's own frames. Every frame of every
//! scene is reconstructed at every cell size by the scatter (1 thread), the full gather and the
//! narrow band (each at every thread count), each run in its own rayon pool; the averages per
//! frame fill Tables 1, 3/4 and 5/6 of Akinci et al. 2012 (see [`super::tables`]).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, anyhow, bail};
use serde::{Deserialize, Serialize};

use splash_sph::bytes::human;
use splash_sph::{Config, Engine, InputFormat, Length, Reconstructor, estimate_spacing};

use crate::memory::{self, reconstruct_measured};
use splash_sph::report::{Build, FrameRecord, Machine, cell_label};

pub struct Options {
    /// Scene directories (every particle file inside is a frame) or particle files (grouped
    /// into scenes by their directory).
    pub inputs: Vec<PathBuf>,
    pub cells: Vec<Length>,
    pub threads: Vec<usize>,
    /// One spacing for every scene, or one per scene in order; estimated where absent.
    pub spacings: Vec<f32>,
    /// Frames per scene, spread evenly over its files; all when None.
    pub frames_per_scene: Option<usize>,
    pub engines: Vec<Engine>,
    /// The parameters; `cell`, `engine`, `threads` and `spacing` are set per run.
    pub config: Config,
}

/// A scene: a name and its frames.
#[derive(Debug, Clone)]
pub struct Scene {
    pub name: String,
    pub frames: Vec<PathBuf>,
}

/// One engine at one thread count on one frame at one cell size.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Run {
    pub scene: String,
    pub frame: String,
    pub cell: String,
    pub engine: String,
    pub threads: usize,
    /// The figures, or None when the run was refused or failed.
    pub record: Option<FrameRecord>,
    /// Why there is no record ("NA" in the tables).
    pub not_available: Option<String>,
}

/// Everything `splash bench` measured: the raw records behind its tables.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct BenchReport {
    pub machine: Machine,
    pub build: Build,
    pub cells: Vec<String>,
    pub threads: Vec<usize>,
    /// Spacing r per scene.
    pub spacings: Vec<(String, f32)>,
    pub max_memory: u64,
    pub config: serde_json::Value,
    pub runs: Vec<Run>,
}

/// Groups the inputs into scenes.
pub fn scenes(inputs: &[PathBuf], frames_per_scene: Option<usize>) -> Result<Vec<Scene>> {
    let mut out: Vec<Scene> = Vec::new();
    for input in inputs {
        let (name, mut frames) = if input.is_dir() {
            let mut files: Vec<PathBuf> = std::fs::read_dir(input)
                .with_context(|| format!("{}: cannot list the directory", input.display()))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.is_file() && InputFormat::from_path(p).is_ok())
                .collect();
            files.sort();
            if files.is_empty() {
                bail!("{}: no particle files in the directory", input.display());
            }
            (dir_name(input), files)
        } else if input.is_file() {
            let dir = input.parent().unwrap_or(Path::new("."));
            (dir_name(dir), vec![input.clone()])
        } else {
            bail!("{}: no such file or directory", input.display());
        };
        match out.iter_mut().find(|s| s.name == name) {
            Some(s) => s.frames.append(&mut frames),
            None => out.push(Scene { name, frames }),
        }
    }
    if let Some(n) = frames_per_scene {
        if n == 0 {
            bail!("--frames-per-scene must be at least 1");
        }
        for s in &mut out {
            s.frames = spread(&s.frames, n);
        }
    }
    Ok(out)
}

fn dir_name(dir: &Path) -> String {
    dir.canonicalize()
        .ok()
        .and_then(|d| d.file_name().map(|n| n.to_string_lossy().into_owned()))
        .unwrap_or_else(|| dir.display().to_string())
}

/// `n` items spread evenly over `all`, first and last included.
fn spread(all: &[PathBuf], n: usize) -> Vec<PathBuf> {
    if n >= all.len() {
        return all.to_vec();
    }
    if n == 1 {
        return vec![all[all.len() / 2].clone()];
    }
    (0..n)
        .map(|k| all[k * (all.len() - 1) / (n - 1)].clone())
        .collect()
}

/// The rows of Tables 3/4: the scatter once (it is serial), then the full gather, the narrow
/// band and Marching Slices at each thread count.
pub fn matrix(engines: &[Engine], threads: &[usize]) -> Vec<(Engine, usize)> {
    let mut rows = Vec::new();
    if engines.contains(&Engine::Scatter) {
        rows.push((Engine::Scatter, 1));
    }
    for e in [Engine::FullGather, Engine::NarrowBand, Engine::Slices] {
        if engines.contains(&e) {
            rows.extend(threads.iter().map(|&t| (e, t)));
        }
    }
    rows
}

/// Runs the matrix; `say` gets one line per run as it finishes.
pub fn run(opts: &Options, mut say: impl FnMut(&str)) -> Result<BenchReport> {
    if opts.threads.contains(&0) {
        bail!("--threads must be at least 1");
    }
    let scenes = scenes(&opts.inputs, opts.frames_per_scene)?;
    if opts.spacings.len() > 1 && opts.spacings.len() != scenes.len() {
        bail!(
            "{} spacings for {} scenes: give one for all, or one per scene in order",
            opts.spacings.len(),
            scenes.len()
        );
    }
    let pools: Vec<(usize, rayon::ThreadPool)> = opts
        .threads
        .iter()
        .map(|&t| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .map(|p| (t, p))
                .context("cannot start the worker threads")
        })
        .collect::<Result<_>>()?;
    let one_thread = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let pool = |t: usize| {
        pools
            .iter()
            .find(|p| p.0 == t)
            .map_or(&one_thread, |p| &p.1)
    };
    let rows = matrix(&opts.engines, &opts.threads);
    let mut runs = Vec::new();
    let mut spacings = Vec::new();
    for (k, scene) in scenes.iter().enumerate() {
        let mut r = opts.spacings.get(k).or(opts.spacings.first()).copied();
        for frame in &scene.frames {
            let name = frame.file_name().map_or_else(
                || frame.display().to_string(),
                |n| n.to_string_lossy().into(),
            );
            let start = Instant::now();
            let particles = splash_sph::read_particles(frame, None)?.positions;
            let read = start.elapsed();
            let spacing = match r {
                Some(r) => r,
                None => {
                    let e = estimate_spacing(&particles).ok_or_else(|| {
                        anyhow!(
                            "{}: cannot estimate the spacing; give --spacing",
                            frame.display()
                        )
                    })?;
                    say(&format!(
                        "{}: estimated spacing r = {e} from {name}",
                        scene.name
                    ));
                    r = Some(e);
                    e
                }
            };
            if !spacings
                .iter()
                .any(|(s, _): &(String, f32)| s == &scene.name)
            {
                spacings.push((scene.name.clone(), spacing));
            }
            for &cell in &opts.cells {
                for &(engine, threads) in &rows {
                    // Each run in its own pool (the reconstructor's would be made per run).
                    let reconstructor = Reconstructor::new(Config {
                        cell,
                        engine,
                        spacing: Some(spacing),
                        threads: None,
                        ..opts.config.clone()
                    })?;
                    memory::reset_peak_rss();
                    let result =
                        pool(threads).install(|| reconstruct_measured(&reconstructor, &particles));
                    let mut run = Run {
                        scene: scene.name.clone(),
                        frame: name.clone(),
                        cell: cell_label(cell),
                        engine: engine.name().into(),
                        threads,
                        record: None,
                        not_available: None,
                    };
                    match result {
                        Ok(rec) => {
                            let mut stats = rec.stats;
                            stats.timings.read = read;
                            let t = stats.timings;
                            say(&format!(
                                "{} {name} cell {cell} {} {threads} thread(s): t_sf {:.3} s, t_tri {:.3} s, {} peak heap",
                                scene.name,
                                engine.name(),
                                t.scalar_field.as_secs_f64(),
                                t.triangulation.as_secs_f64(),
                                human(stats.heap_peak as u64)
                            ));
                            run.record = Some(FrameRecord::new(
                                &scene.name,
                                &name,
                                engine.name(),
                                &cell_label(cell),
                                &stats,
                            ));
                        }
                        Err(e) => {
                            let reason = format!("{e:#}");
                            say(&format!(
                                "{} {name} cell {cell} {} {threads} thread(s): NA: {reason}",
                                scene.name,
                                engine.name()
                            ));
                            run.not_available = Some(reason);
                        }
                    }
                    runs.push(run);
                }
            }
        }
    }
    Ok(BenchReport {
        machine: Machine::this(),
        build: crate::this_build(),
        cells: opts.cells.iter().map(|&c| cell_label(c)).collect(),
        threads: opts.threads.clone(),
        spacings,
        max_memory: opts
            .config
            .max_memory
            .map_or_else(splash_sph::bytes::default_limit, |b| b.0),
        config: serde_json::to_value(&opts.config)?,
        runs,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_spread_evenly() {
        let all: Vec<PathBuf> = (0..21).map(|i| PathBuf::from(format!("f{i:02}"))).collect();
        let names = |v: Vec<PathBuf>| -> Vec<String> {
            v.iter().map(|p| p.display().to_string()).collect()
        };
        assert_eq!(names(spread(&all, 3)), ["f00", "f10", "f20"]);
        assert_eq!(names(spread(&all, 1)), ["f10"]);
        assert_eq!(spread(&all, 50).len(), 21);
    }

    #[test]
    fn matrix_has_the_paper_rows() {
        let rows = matrix(&Engine::ALL, &[1, 2]);
        let names: Vec<String> = rows
            .iter()
            .map(|(e, t)| format!("{}-{t}", e.name()))
            .collect();
        assert_eq!(
            names,
            [
                "scatter-1",
                "full-gather-1",
                "full-gather-2",
                "narrow-band-1",
                "narrow-band-2",
                "slices-1",
                "slices-2"
            ]
        );
    }
}
