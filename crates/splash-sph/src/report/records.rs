//! Reports of a run: one record per frame, their average per frame (as the paper gives all
//! data), the machine, the build and the resolved configuration; written as JSON, CSV or
//! Markdown by the file's extension. `splash recon --report` writes [`Report::of_run`]'s, and
//! `splash bench` keeps [`FrameRecord`]s of its runs.

use std::path::Path;

use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};

use crate::bytes::human;
use crate::error::{Error, Result};
use crate::pipeline::FrameOutcome;
use crate::{Config, FrameStats, Length};

/// The figures of one frame, all numbers so that they can be averaged: [`FrameStats`] as a
/// report gives it. Times in seconds, memory in bytes.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct Figures {
    /// [`FrameStats::particles`].
    pub particles: f64,
    /// [`FrameStats::particles_outside_box`].
    pub particles_outside_box: f64,
    /// [`FrameStats::surface_particles`].
    pub surface_particles: f64,
    /// #particles_surf / #particles_total (Table 1).
    pub surface_particle_ratio: f64,
    /// Vertices of the full grid along x ([`FrameStats::grid`]).
    pub grid_res_x: f64,
    /// Along y.
    pub grid_res_y: f64,
    /// Along z.
    pub grid_res_z: f64,
    /// Vertices of the full grid (the particles' box widened by the support).
    pub grid_vertices: f64,
    /// Vertices that got a field value: the band for the narrow band, the grid otherwise.
    pub surface_vertices: f64,
    /// #vertices_surf / #vertices_total (Table 1).
    pub surface_vertex_ratio: f64,
    /// Cells the surface crosses, each triangulated.
    pub cells_triangulated: f64,
    /// Triangles of the mesh.
    pub triangles: f64,
    /// Vertices of the mesh.
    pub output_vertices: f64,
    /// Worker threads of the pool that reconstructed the frame.
    pub threads: f64,
    /// Reading the particle file.
    pub t_read: f64,
    /// Sorting the handler array.
    pub t_handler_array: f64,
    /// t_sp.
    pub t_surface_particles: f64,
    /// The band of surface vertices.
    pub t_band: f64,
    /// t_sf.
    pub t_scalar_field: f64,
    /// t_tri.
    pub t_triangulation: f64,
    /// Post-processing the mesh (`[post]`: smoothing, volumes, box, small parts, decimation);
    /// 0 when it did not run (`--raw` without `--mesh-aabb`, `--min-component`, `--decimate`).
    pub t_post: f64,
    /// Writing the mesh.
    pub t_write: f64,
    /// Reading, reconstructing and writing.
    pub t_total: f64,
    /// Exact peak heap of the reconstruction (counting allocator), input particles excluded.
    pub heap_peak: f64,
    /// The engine's estimate of its heap, checked against --max-memory before it allocated.
    pub heap_planned: f64,
    /// Peak heap of each stage ([`StageHeap`](super::StageHeap)).
    pub heap_handler_array: f64,
    /// See `heap_handler_array`.
    pub heap_surface_particles: f64,
    /// See `heap_handler_array`.
    pub heap_band: f64,
    /// See `heap_handler_array`.
    pub heap_scalar_field: f64,
    /// See `heap_handler_array`.
    pub heap_triangulation: f64,
    /// See `heap_handler_array`.
    pub heap_post: f64,
    /// Peak resident set size of the process (VmHWM) after the frame.
    pub peak_rss: f64,
    /// The slices engine's blocks (zeros for the other engines): count, most slices cached at
    /// once, per-block peak render and cache memory (largest and mean), and both summed over
    /// the blocks in flight at once ([`SlicesFigures`](super::SlicesFigures)).
    pub slices_blocks: f64,
    /// See `slices_blocks`.
    pub slices_peak_slices: f64,
    /// See `slices_blocks`.
    pub slices_render_bytes_max: f64,
    /// See `slices_blocks`.
    pub slices_render_bytes_mean: f64,
    /// See `slices_blocks`.
    pub slices_cache_bytes_max: f64,
    /// See `slices_blocks`.
    pub slices_cache_bytes_mean: f64,
    /// See `slices_blocks`.
    pub slices_in_flight_peak: f64,
}

impl Figures {
    /// The figures of `s`.
    pub fn of(s: &FrameStats) -> Figures {
        let ratio = |a: f64, b: f64| if b > 0.0 { a / b } else { 0.0 };
        let t = &s.timings;
        let h = &s.stage_heap;
        let secs = |d: std::time::Duration| d.as_secs_f64();
        let grid_vertices = s.grid_vertices() as f64;
        Figures {
            particles: s.particles as f64,
            particles_outside_box: s.particles_outside_box as f64,
            surface_particles: s.surface_particles as f64,
            surface_particle_ratio: ratio(s.surface_particles as f64, s.particles as f64),
            grid_res_x: s.grid[0] as f64,
            grid_res_y: s.grid[1] as f64,
            grid_res_z: s.grid[2] as f64,
            grid_vertices,
            surface_vertices: s.surface_vertices as f64,
            surface_vertex_ratio: ratio(s.surface_vertices as f64, grid_vertices),
            cells_triangulated: s.surface_cells as f64,
            triangles: s.triangles as f64,
            output_vertices: s.vertices as f64,
            threads: s.threads as f64,
            t_read: secs(t.read),
            t_handler_array: secs(t.handler_array),
            t_surface_particles: secs(t.surface_particles),
            t_band: secs(t.band),
            t_scalar_field: secs(t.scalar_field),
            t_triangulation: secs(t.triangulation),
            t_post: secs(t.post),
            t_write: secs(t.write),
            t_total: secs(t.read + t.reconstruction() + t.write),
            heap_peak: s.heap_peak as f64,
            heap_planned: s.planned_bytes as f64,
            heap_handler_array: h.handler_array as f64,
            heap_surface_particles: h.surface_particles as f64,
            heap_band: h.band as f64,
            heap_scalar_field: h.scalar_field as f64,
            heap_triangulation: h.triangulation as f64,
            heap_post: h.post as f64,
            peak_rss: s.peak_rss as f64,
            slices_blocks: s.slices.blocks as f64,
            slices_peak_slices: s.slices.peak_slices as f64,
            slices_render_bytes_max: s.slices.render_bytes_max as f64,
            slices_render_bytes_mean: s.slices.render_bytes_mean as f64,
            slices_cache_bytes_max: s.slices.cache_bytes_max as f64,
            slices_cache_bytes_mean: s.slices.cache_bytes_mean as f64,
            slices_in_flight_peak: s.slices.in_flight_peak as f64,
        }
    }

    /// The mean of every figure; zeros for no frames.
    pub fn mean(all: &[Figures]) -> Figures {
        if all.is_empty() {
            return Figures::default();
        }
        let mut sum = Map::new();
        for f in all {
            for (k, v) in as_map(f) {
                let add = v.as_f64().unwrap_or(0.0);
                let acc = sum.entry(k).or_insert(Value::from(0.0));
                *acc = Value::from(acc.as_f64().unwrap_or(0.0) + add);
            }
        }
        for v in sum.values_mut() {
            *v = Value::from(v.as_f64().unwrap_or(0.0) / all.len() as f64);
        }
        serde_json::from_value(Value::Object(sum)).expect("same fields")
    }

    /// Field names and values, in declaration order.
    pub fn fields(&self) -> Vec<(String, f64)> {
        as_map(self)
            .into_iter()
            .map(|(k, v)| (k, v.as_f64().unwrap_or(0.0)))
            .collect()
    }
}

fn as_map(f: &Figures) -> Map<String, Value> {
    match serde_json::to_value(f).expect("numbers serialize") {
        Value::Object(m) => m,
        _ => unreachable!("a struct serializes to an object"),
    }
}

/// One frame reconstructed by one engine at one cell size with some threads.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FrameRecord {
    /// The scene: the name of the frame's folder.
    pub scene: String,
    /// The frame's file name.
    pub frame: String,
    /// The engine's name ([`Engine::name`](crate::Engine::name)).
    pub engine: String,
    /// The cell as configured (e.g. "r/2", see [`cell_label`]).
    pub cell: String,
    /// The cell in world units.
    pub cell_world: f32,
    /// The particle spacing r used, given or estimated.
    pub spacing: f32,
    /// The frame's figures.
    #[serde(flatten)]
    pub figures: Figures,
}

impl FrameRecord {
    /// The record of `stats`, the figures of frame `frame` of `scene`.
    pub fn new(scene: &str, frame: &str, engine: &str, cell: &str, stats: &FrameStats) -> Self {
        FrameRecord {
            scene: scene.into(),
            frame: frame.into(),
            engine: engine.into(),
            cell: cell.into(),
            cell_world: stats.cell,
            spacing: stats.spacing,
            figures: Figures::of(stats),
        }
    }
}

/// Where the numbers were measured.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Machine {
    /// The CPU's model name (`/proc/cpuinfo`), else "unknown".
    pub cpu_model: String,
    /// Logical CPUs available to the process.
    pub cores: usize,
    /// The machine's memory in bytes (0 where unknown).
    pub memory_total: u64,
    /// The operating system (`std::env::consts::OS`).
    pub os: String,
}

impl Machine {
    /// The machine this runs on.
    pub fn this() -> Machine {
        let cpu_model = std::fs::read_to_string("/proc/cpuinfo")
            .ok()
            .and_then(|t| {
                t.lines()
                    .find(|l| l.starts_with("model name"))
                    .and_then(|l| l.split_once(':'))
                    .map(|(_, v)| v.trim().to_string())
            })
            .unwrap_or_else(|| "unknown".into());
        Machine {
            cpu_model,
            cores: std::thread::available_parallelism().map_or(1, |n| n.get()),
            memory_total: crate::bytes::machine_memory().unwrap_or(0),
            os: std::env::consts::OS.into(),
        }
    }
}

/// What was measured: the program's version and, where known at build time, its git revision.
/// The program gives it: the command line its own, with its counting allocator.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Build {
    /// The program's version.
    pub version: String,
    /// Its git revision, where known.
    pub git_revision: Option<String>,
    /// "release" or "debug" (a build with debug assertions).
    pub profile: String,
    /// Whether heap figures come from the counting allocator.
    pub heap_counted: bool,
}

/// A whole report.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Report {
    /// Where it ran.
    pub machine: Machine,
    /// What ran.
    pub build: Build,
    /// Worker threads of the run (per record in `frames` too).
    pub threads_used: usize,
    /// The resolved configuration ([`Config`]) as JSON.
    pub config: Value,
    /// One record per frame.
    pub frames: Vec<FrameRecord>,
    /// Mean of every figure over the frames (failed frames excluded).
    pub average: Figures,
}

/// The formats a report is written in, by its file's extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReportFormat {
    /// `.json`: the whole [`Report`].
    Json,
    /// `.csv`: one row per frame and a last row `average`.
    Csv,
    /// `.md`: headline columns per frame, every figure of the average, the configuration.
    Markdown,
}

impl ReportFormat {
    /// The format of `path`'s extension (any case): `.json`, `.csv` or `.md`.
    pub fn from_path(path: &Path) -> Option<ReportFormat> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("json") => Some(ReportFormat::Json),
            Some("csv") => Some(ReportFormat::Csv),
            Some("md") => Some(ReportFormat::Markdown),
            _ => None,
        }
    }
}

impl Report {
    /// A report of `frames` on this machine, their average computed.
    pub fn new(
        build: Build,
        config: Value,
        threads_used: usize,
        frames: Vec<FrameRecord>,
    ) -> Report {
        let figures: Vec<Figures> = frames.iter().map(|f| f.figures.clone()).collect();
        Report {
            machine: Machine::this(),
            build,
            threads_used,
            config,
            average: Figures::mean(&figures),
            frames,
        }
    }

    /// The report of a run of `config` (the configuration as resolved, threads included) over
    /// frames, as `splash recon --report` writes it: one record per reconstructed frame, failed
    /// frames left out, its scene the name of the frame's folder; the configuration with the
    /// spacing used (given or estimated, the first frame's) and the world cell added. The
    /// threads used are those of the current rayon pool.
    pub fn of_run(outcomes: &[FrameOutcome], config: &Config, build: Build) -> Result<Report> {
        let records: Vec<FrameRecord> = outcomes
            .iter()
            .filter_map(|o| {
                let stats = o.result.as_ref().ok()?;
                let scene = o
                    .input
                    .parent()
                    .and_then(|p| p.file_name())
                    .map_or(String::new(), |n| n.to_string_lossy().into_owned());
                let frame = o
                    .input
                    .file_name()
                    .map_or(String::new(), |n| n.to_string_lossy().into_owned());
                Some(FrameRecord::new(
                    &scene,
                    &frame,
                    config.engine.name(),
                    &cell_label(config.cell),
                    stats,
                ))
            })
            .collect();
        let mut resolved = serde_json::to_value(config)
            .map_err(|e| Error::config(format!("cannot give the configuration as JSON: {e}")))?;
        if let (Some(obj), Some(first)) = (resolved.as_object_mut(), records.first()) {
            // The spacing used (given or estimated) and the world cell, besides the config.
            obj.insert("spacing_used".into(), first.spacing.into());
            obj.insert("cell_world".into(), first.cell_world.into());
            obj.insert("engine".into(), config.engine.name().into());
        }
        Ok(Report::new(
            build,
            resolved,
            rayon::current_num_threads(),
            records,
        ))
    }

    /// Writes the report in the format of `path`'s extension ([`ReportFormat::from_path`]).
    pub fn write(&self, path: &Path) -> Result<()> {
        let Some(format) = ReportFormat::from_path(path) else {
            bail_config!("{}: a report ends in .json, .csv or .md", path.display());
        };
        std::fs::write(path, self.text(format)).map_err(|e| Error::Io {
            path: path.to_path_buf(),
            message: format!("{}: cannot write the report: {e}", path.display()),
            io_error: e,
        })
    }

    /// The report's text in `format`.
    pub fn text(&self, format: ReportFormat) -> String {
        match format {
            ReportFormat::Json => self.json(),
            ReportFormat::Csv => self.csv(),
            ReportFormat::Markdown => self.markdown(),
        }
    }

    /// The whole report as pretty-printed JSON, ending in a newline.
    pub fn json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a report serializes") + "\n"
    }

    /// One row per frame and a last row `average`; the machine and build as `#` comments.
    pub fn csv(&self) -> String {
        let mut out = format!(
            "# cpu: {}; cores: {}; threads: {}; splash {} ({})\n",
            self.machine.cpu_model,
            self.machine.cores,
            self.threads_used,
            self.build.version,
            self.build
                .git_revision
                .as_deref()
                .unwrap_or("revision unknown")
        );
        let names: Vec<String> = self.average.fields().into_iter().map(|f| f.0).collect();
        out += &format!(
            "scene,frame,engine,cell,cell_world,spacing,{}\n",
            names.join(",")
        );
        let row = |r: &FrameRecord| {
            let nums: Vec<String> = r.figures.fields().iter().map(|f| num(f.1)).collect();
            format!(
                "{},{},{},{},{},{},{}\n",
                csv_field(&r.scene),
                csv_field(&r.frame),
                r.engine,
                r.cell,
                r.cell_world,
                r.spacing,
                nums.join(",")
            )
        };
        for r in &self.frames {
            out += &row(r);
        }
        if let Some(first) = self.frames.first() {
            out += &row(&FrameRecord {
                scene: first.scene.clone(),
                frame: "average".into(),
                figures: self.average.clone(),
                ..first.clone()
            });
        }
        out
    }

    /// Headline columns per frame plus the average, then every figure of the average.
    pub fn markdown(&self) -> String {
        let m = &self.machine;
        let mut out = format!(
            "# splash report\n\n- machine: {} ({} logical cores, {} memory), {}\n- build: splash {} ({}, {}{})\n- threads used: {}\n\n",
            m.cpu_model,
            m.cores,
            human(m.memory_total),
            m.os,
            self.build.version,
            self.build
                .git_revision
                .as_deref()
                .unwrap_or("revision unknown"),
            self.build.profile,
            if self.build.heap_counted {
                ""
            } else {
                ", heap not counted"
            },
            self.threads_used
        );
        out += "| frame | engine | cell | #particles | surf/total particles | grid res. | surf/total vertices | #triangles | t_sp [s] | t_sf [s] | t_tri [s] | t_post [s] | total [s] | peak heap | peak RSS |\n";
        out += "|---|---|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
        let row = |name: &str, engine: &str, cell: &str, f: &Figures| {
            format!(
                "| {name} | {engine} | {cell} | {:.0} | {:.3} | {:.0} × {:.0} × {:.0} | {:.3} | {:.0} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {} | {} |\n",
                f.particles,
                f.surface_particle_ratio,
                f.grid_res_x,
                f.grid_res_y,
                f.grid_res_z,
                f.surface_vertex_ratio,
                f.triangles,
                f.t_surface_particles,
                f.t_scalar_field,
                f.t_triangulation,
                f.t_post,
                f.t_total,
                human(f.heap_peak as u64),
                human(f.peak_rss as u64),
            )
        };
        for r in &self.frames {
            out += &row(&r.frame, &r.engine, &r.cell, &r.figures);
        }
        if let Some(first) = self.frames.first() {
            out += &row("**average**", &first.engine, &first.cell, &self.average);
        }
        out += "\n## Average per frame, every figure\n\n| figure | value |\n|---|---:|\n";
        for (k, v) in self.average.fields() {
            out += &format!("| {k} | {} |\n", num(v));
        }
        out += "\n## Configuration\n\n```json\n";
        out += &serde_json::to_string_pretty(&self.config).unwrap_or_default();
        out += "\n```\n";
        out
    }
}

fn num(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e15 {
        format!("{v:.0}")
    } else {
        format!("{v:.6}")
    }
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// A cell size as the paper writes it: r, r/2, r/4, 2r, or the length.
pub fn cell_label(cell: Length) -> String {
    match cell {
        Length::Spacings(0.5) => "r/2".into(),
        Length::Spacings(0.25) => "r/4".into(),
        other => other.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;

    use super::*;

    fn outcome(input: &str, result: Result<FrameStats>) -> FrameOutcome {
        FrameOutcome {
            input: PathBuf::from(input),
            output: PathBuf::from("out.obj"),
            frame: None,
            result,
        }
    }

    #[test]
    fn a_run_report_averages_the_reconstructed_frames() {
        let stats = |particles, triangles| FrameStats {
            spacing: 0.5,
            cell: 0.25,
            particles,
            triangles,
            ..FrameStats::default()
        };
        let outcomes = [
            outcome("scene, one/f_1.ply", Ok(stats(10, 4))),
            outcome("scene, one/f_2.ply", Err(Error::input("broken"))),
            outcome("scene, one/f_3.ply", Ok(stats(30, 8))),
        ];
        let config = Config {
            spacing: Some(0.5),
            ..Config::default()
        };
        let build = Build {
            version: "1".into(),
            git_revision: None,
            profile: "release".into(),
            heap_counted: false,
        };
        let report = Report::of_run(&outcomes, &config, build).unwrap();
        assert_eq!(report.frames.len(), 2);
        assert_eq!(report.frames[1].frame, "f_3.ply");
        assert_eq!(report.frames[0].scene, "scene, one");
        assert_eq!(report.frames[0].cell, "r/2");
        assert_eq!(report.average.particles, 20.0);
        assert_eq!(report.average.triangles, 6.0);
        assert_eq!(report.config["spacing_used"], 0.5);
        assert_eq!(report.config["cell_world"], 0.25);
        let csv = report.text(ReportFormat::Csv);
        assert_eq!(csv.lines().count(), 5, "{csv}");
        assert!(
            csv.contains("\n\"scene, one\",average,narrow-band,r/2,"),
            "{csv}"
        );
        assert!(report.json().ends_with("}\n"));
        assert_eq!(
            ReportFormat::from_path(Path::new("a.MD")),
            Some(ReportFormat::Markdown)
        );
        assert_eq!(ReportFormat::from_path(Path::new("a.txt")), None);
    }
}
