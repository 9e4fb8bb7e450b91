//! The Markdown tables of `splash bench`, in the shapes of Akinci et al. 2012: Table 1 (scenes
//! and grids), Tables 3/4 (engines per scene and cell size) and Tables 5/6 (scenes per cell
//! size). All figures are averages per frame; a row some of whose runs were refused reads "NA"
//! with the reason.

use super::engines::{BenchReport, Run, matrix};
use splash_sph::Engine;
use splash_sph::bytes::human;
use splash_sph::report::Figures;

/// Mean figures of the runs matching a scene, cell, engine and thread count; Err with the first
/// reason when a run has none, None when there are no such runs.
fn average(
    report: &BenchReport,
    scene: &str,
    cell: &str,
    engine: Engine,
    threads: Option<usize>,
) -> Option<Result<Figures, String>> {
    let runs: Vec<&Run> = report
        .runs
        .iter()
        .filter(|r| {
            r.scene == scene
                && r.cell == cell
                && r.engine == engine.name()
                && threads.is_none_or(|t| r.threads == t)
        })
        .collect();
    if runs.is_empty() {
        return None;
    }
    if let Some(reason) = runs.iter().find_map(|r| r.not_available.clone()) {
        return Some(Err(reason));
    }
    let figures: Vec<Figures> = runs
        .iter()
        .filter_map(|r| r.record.as_ref().map(|f| f.figures.clone()))
        .collect();
    Some(Ok(Figures::mean(&figures)))
}

fn scenes(report: &BenchReport) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for r in &report.runs {
        if !out.contains(&r.scene) {
            out.push(r.scene.clone());
        }
    }
    out
}

fn count(n: f64) -> String {
    if n >= 1e6 {
        format!("{:.2}m", n / 1e6)
    } else if n >= 1e3 {
        format!("{:.0}k", n / 1e3)
    } else {
        format!("{n:.0}")
    }
}

fn secs(s: f64) -> String {
    if s >= 10.0 {
        format!("{s:.1}")
    } else {
        format!("{s:.3}")
    }
}

fn frames_of(report: &BenchReport, scene: &str) -> usize {
    let mut frames: Vec<&str> = report
        .runs
        .iter()
        .filter(|r| r.scene == scene)
        .map(|r| r.frame.as_str())
        .collect();
    frames.sort_unstable();
    frames.dedup();
    frames.len()
}

/// Table 1: scene, #particles, surface/total particles, and per cell size surface/total
/// vertices, #triangles and grid resolution (vertices per axis), from the narrow band at the
/// most threads.
pub fn table1(report: &BenchReport) -> String {
    let threads = report.threads.iter().max().copied();
    let mut head =
        "| scene | frames | #particles | #particles_surf / #particles_total |".to_string();
    let mut rule = "|---|---:|---:|---:|".to_string();
    for c in &report.cells {
        head += &format!(
            " cell {c}: #vertices_surf / #vertices_total | cell {c}: #triangles | cell {c}: grid res. |"
        );
        rule += "---:|---:|---|";
    }
    let mut out = format!(
        "**Table 1 shape.** General information of the scenes, average per frame.\n\n{head}\n{rule}\n"
    );
    for scene in scenes(report) {
        let first = report
            .cells
            .iter()
            .find_map(|c| average(report, &scene, c, Engine::NarrowBand, threads)?.ok());
        let Some(f) = first else {
            continue;
        };
        out += &format!(
            "| {scene} | {} | {} | {:.3} |",
            frames_of(report, &scene),
            count(f.particles),
            f.surface_particle_ratio
        );
        for c in &report.cells {
            match average(report, &scene, c, Engine::NarrowBand, threads) {
                Some(Ok(f)) => {
                    out += &format!(
                        " {:.3} | {} | {:.0} × {:.0} × {:.0} |",
                        f.surface_vertex_ratio,
                        count(f.triangles),
                        f.grid_res_x,
                        f.grid_res_y,
                        f.grid_res_z
                    )
                }
                _ => out += " NA | NA | NA |",
            }
        }
        out += "\n";
    }
    out
}

fn row_name(engine: Engine, threads: usize) -> String {
    let t = if threads == 1 {
        "1 thread".to_string()
    } else {
        format!("{threads} threads")
    };
    match engine {
        Engine::Scatter => "scatter".into(),
        Engine::FullGather => format!("Z-index-{t}"),
        Engine::NarrowBand => format!("our-{t}"),
        Engine::Slices => format!("slices-{t}"),
    }
}

/// Tables 3/4: per scene and cell size, rows scatter, Z-index (full gather) and ours (narrow
/// band) at each thread count; columns t_sf, t_tri, memory (peak heap) and peak RSS.
pub fn tables34(report: &BenchReport) -> String {
    let mut out = String::new();
    let engines: Vec<Engine> = Engine::ALL
        .into_iter()
        .filter(|e| report.runs.iter().any(|r| r.engine == e.name()))
        .collect();
    let rows = matrix(&engines, &report.threads);
    for scene in scenes(report) {
        for c in &report.cells {
            out += &format!(
                "**Table 3/4 shape: {scene}, cell size {c}.** Average per frame over {} frame(s); memory is the reconstruction's peak heap, RSS the process's peak resident set.\n\n",
                frames_of(report, &scene)
            );
            out += "| method | t_sf [sec] | t_tri [sec] | memory [MB] | peak RSS [MB] |\n|---|---:|---:|---:|---:|\n";
            for &(engine, threads) in &rows {
                let name = row_name(engine, threads);
                match average(report, &scene, c, engine, Some(threads)) {
                    None => {}
                    Some(Ok(f)) => {
                        out += &format!(
                            "| {name} | {} | {} | {:.1} | {:.1} |\n",
                            secs(f.t_scalar_field),
                            secs(f.t_triangulation),
                            f.heap_peak / 1e6,
                            f.peak_rss / 1e6
                        )
                    }
                    Some(Err(reason)) => {
                        out += &format!("| {name} | NA | NA | NA | NA ({reason}) |\n")
                    }
                }
            }
            out += "\n";
        }
    }
    out
}

/// Tables 5/6: per cell size, rows scenes; columns t_sf at each thread count, t_tri (at the
/// most threads) and memory, for the narrow band.
pub fn tables56(report: &BenchReport) -> String {
    let mut out = String::new();
    let most = report.threads.iter().max().copied().unwrap_or(1);
    for c in &report.cells {
        out += &format!(
            "**Table 5/6 shape: cell size {c}.** Narrow band, average per frame.\n\n| scene |"
        );
        let mut rule = "|---|".to_string();
        for t in &report.threads {
            out += &format!(
                " t_sf-CPU {} |",
                row_name(Engine::NarrowBand, *t).trim_start_matches("our-")
            );
            rule += "---:|";
        }
        out += " t_tri | mem_CPU [MB] | peak RSS [MB] |\n";
        out += &format!("{rule}---:|---:|---:|\n");
        for scene in scenes(report) {
            out += &format!("| {scene} |");
            for &t in &report.threads {
                match average(report, &scene, c, Engine::NarrowBand, Some(t)) {
                    Some(Ok(f)) => out += &format!(" {} sec |", secs(f.t_scalar_field)),
                    _ => out += " NA |",
                }
            }
            match average(report, &scene, c, Engine::NarrowBand, Some(most)) {
                Some(Ok(f)) => {
                    out += &format!(
                        " {} sec | {:.1} | {:.1} |\n",
                        secs(f.t_triangulation),
                        f.heap_peak / 1e6,
                        f.peak_rss / 1e6
                    )
                }
                _ => out += " NA | NA | NA |\n",
            }
        }
        out += "\n";
    }
    out
}

/// All tables, preceded by the machine and build.
pub fn markdown(report: &BenchReport) -> String {
    let m = &report.machine;
    let b = &report.build;
    let mut out = format!(
        "Machine: {} ({} logical cores, {}); splash {} ({}, {}); threads {:?}; --max-memory {}; spacing {}.\n\n",
        m.cpu_model,
        m.cores,
        human(m.memory_total),
        b.version,
        b.git_revision.as_deref().unwrap_or("revision unknown"),
        b.profile,
        report.threads,
        human(report.max_memory),
        report
            .spacings
            .iter()
            .map(|(s, r)| format!("{s}: r = {r}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    out += &table1(report);
    out += "\n";
    out += &tables34(report);
    out += &tables56(report);
    out
}
