//! Reports of a run: one record per frame, their average per frame (as the paper gives all
//! data), the machine, the build and the resolved configuration; written as JSON, CSV or
//! Markdown by the file's extension.

use std::path::Path;

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};

use splash_sph::FrameStats;
use splash_sph::bytes::human;

use crate::memory;

/// The figures of one frame, all numbers so that they can be averaged. Times in seconds,
/// memory in bytes.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct Figures {
    pub particles: f64,
    pub particles_outside_box: f64,
    pub surface_particles: f64,
    /// #particles_surf / #particles_total (Table 1).
    pub surface_particle_ratio: f64,
    pub grid_res_x: f64,
    pub grid_res_y: f64,
    pub grid_res_z: f64,
    /// Vertices of the full grid (the particles' box widened by the support).
    pub grid_vertices: f64,
    /// Vertices that got a field value: the band for the narrow band, the grid otherwise.
    pub surface_vertices: f64,
    /// #vertices_surf / #vertices_total (Table 1).
    pub surface_vertex_ratio: f64,
    /// Cells the surface crosses, each triangulated.
    pub cells_triangulated: f64,
    pub triangles: f64,
    pub output_vertices: f64,
    pub threads: f64,
    pub t_read: f64,
    pub t_handler_array: f64,
    /// t_sp.
    pub t_surface_particles: f64,
    pub t_band: f64,
    /// t_sf.
    pub t_scalar_field: f64,
    /// t_tri.
    pub t_triangulation: f64,
    /// Post-processing the mesh (`[post]`: smoothing, volumes, box, small parts, decimation);
    /// 0 when it did not run (`--raw` without `--mesh-aabb`, `--min-component`, `--decimate`).
    pub t_post: f64,
    pub t_write: f64,
    pub t_total: f64,
    /// Exact peak heap of the reconstruction (counting allocator), input particles excluded.
    pub heap_peak: f64,
    /// The engine's estimate of its heap, checked against --max-memory before it allocated.
    pub heap_planned: f64,
    pub heap_handler_array: f64,
    pub heap_surface_particles: f64,
    pub heap_band: f64,
    pub heap_scalar_field: f64,
    pub heap_triangulation: f64,
    pub heap_post: f64,
    /// Peak resident set size of the process (VmHWM) after the frame.
    pub peak_rss: f64,
    /// The slices engine's blocks (zeros for the other engines): count, most slices cached at
    /// once, per-block peak render and cache memory (largest and mean), and both summed over
    /// the blocks in flight at once.
    pub slices_blocks: f64,
    pub slices_peak_slices: f64,
    pub slices_render_bytes_max: f64,
    pub slices_render_bytes_mean: f64,
    pub slices_cache_bytes_max: f64,
    pub slices_cache_bytes_mean: f64,
    pub slices_in_flight_peak: f64,
}

impl Figures {
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
    pub scene: String,
    pub frame: String,
    pub engine: String,
    /// The cell as configured (e.g. "r/2") and in world units.
    pub cell: String,
    pub cell_world: f32,
    pub spacing: f32,
    #[serde(flatten)]
    pub figures: Figures,
}

impl FrameRecord {
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
    pub cpu_model: String,
    /// Logical CPUs available to the process.
    pub cores: usize,
    pub memory_total: u64,
    pub os: String,
}

impl Machine {
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
            memory_total: splash_sph::bytes::machine_memory().unwrap_or(0),
            os: std::env::consts::OS.into(),
        }
    }
}

/// What was measured: the crate version and, where known at build time, its git revision.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Build {
    pub version: String,
    pub git_revision: Option<String>,
    pub profile: String,
    /// Whether heap figures come from the counting allocator.
    pub heap_counted: bool,
}

impl Build {
    pub fn this() -> Build {
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
}

/// A whole report.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Report {
    pub machine: Machine,
    pub build: Build,
    /// Worker threads of the run (per record in `frames` too).
    pub threads_used: usize,
    /// The resolved configuration (`Config`), or the bench's settings.
    pub config: Value,
    pub frames: Vec<FrameRecord>,
    /// Mean of every figure over the frames (failed frames excluded).
    pub average: Figures,
}

impl Report {
    pub fn new(config: Value, threads_used: usize, frames: Vec<FrameRecord>) -> Report {
        let figures: Vec<Figures> = frames.iter().map(|f| f.figures.clone()).collect();
        Report {
            machine: Machine::this(),
            build: Build::this(),
            threads_used,
            config,
            average: Figures::mean(&figures),
            frames,
        }
    }

    /// Writes the report in the format of `path`'s extension: .json, .csv or .md.
    pub fn write(&self, path: &Path) -> Result<()> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        let text = match ext.as_deref() {
            Some("json") => serde_json::to_string_pretty(self)? + "\n",
            Some("csv") => self.csv(),
            Some("md") => self.markdown(),
            _ => bail!("{}: a report ends in .json, .csv or .md", path.display()),
        };
        std::fs::write(path, text)
            .with_context(|| format!("{}: cannot write the report", path.display()))
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

/// Fails early, before any frame is reconstructed, when `path` names no report format.
pub fn check_report_path(path: &Path) -> Result<()> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("json" | "csv" | "md") => Ok(()),
        _ => bail!(
            "--report {}: a report ends in .json, .csv or .md",
            path.display()
        ),
    }
}
