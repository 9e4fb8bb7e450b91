//! The three engines (narrow band, full gather, scatter) give the same mesh, the full-grid
//! engines refuse grids above --max-memory, the memory figures behave, and `splash recon
//! --report` and `splash bench` report the right counts and tables.
//!
//! One test binary for all of it (each costs a link), run one test at a time: the counting
//! allocator counts the whole process, so the memory test must run alone.

mod common;

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::{Mutex, MutexGuard};

use common::{fixture, lattice_ball, offsets, params, same_mesh};
use glam::Vec3;
use serde_json::Value;
use splash::recon::full_grid::{Grid, needed_bytes};
use splash::recon::{Engine, Limits, reconstruct, reconstruct_with};

/// Held by every test: one at a time.
fn serial() -> MutexGuard<'static, ()> {
    static LOCK: Mutex<()> = Mutex::new(());
    LOCK.lock().unwrap_or_else(|e| e.into_inner())
}

const R: f32 = 0.01;

fn assert_engines_agree(ps: &[Vec3], r: f32, cell: &str, what: &str) {
    let p = params(r, cell);
    let band = reconstruct(ps, &p, Engine::NarrowBand).unwrap();
    let full = reconstruct(ps, &p, Engine::FullGather).unwrap();
    let scatter = reconstruct(ps, &p, Engine::Scatter).unwrap();
    assert!(band.stats.triangles > 0, "{what}: empty mesh");
    assert_eq!(
        band.mesh.triangles.len(),
        full.mesh.triangles.len(),
        "{what}"
    );
    same_mesh(&band.mesh, &full.mesh, 0.0).unwrap_or_else(|e| panic!("{what}, full gather: {e}"));
    // Where the fluid lies against a wall of the simulation box, the surface runs almost along
    // grid edges and the field changes little along them: there a last-bit difference of the
    // field moves a vertex by up to ~2e-3 cells (measured on frame_0040: 70 of 25k vertices
    // beyond 1e-4 cells, all on the walls). Hence 1e-2 cells for every vertex, 1e-4 cells for
    // 99% of them, and the same topology.
    same_mesh(&band.mesh, &scatter.mesh, 1e-2 * p.cell)
        .unwrap_or_else(|e| panic!("{what}, scatter: {e}"));
    let off = offsets(&band.mesh, &scatter.mesh, p.cell);
    let far = off.iter().filter(|&&o| o > 1e-4).count();
    assert!(
        far * 100 <= off.len(),
        "{what}, scatter: {far} of {} vertices are more than 1e-4 cells off",
        off.len()
    );
    assert_eq!(band.stats.grid, full.stats.grid, "{what}");
    assert_eq!(band.stats.grid, scatter.stats.grid, "{what}");
}

#[test]
fn three_engines_agree_on_a_ball_with_splashes() {
    let _serial = serial();
    let mut ps = lattice_ball(Vec3::new(0.3, -0.2, 0.1), 6.0 * R, R);
    ps.push(Vec3::new(0.3 + 9.5 * R, -0.2, 0.1));
    ps.extend(lattice_ball(
        Vec3::new(0.3, -0.2 + 11.0 * R, 0.1),
        1.5 * R,
        R,
    ));
    for cell in ["r", "r/2"] {
        assert_engines_agree(&ps, R, cell, &format!("ball at cell {cell}"));
    }
}

#[test]
fn three_engines_agree_on_a_real_frame() {
    let _serial = serial();
    let ps = splash::io::read_particles(&fixture("frame_0040.ply"), None).unwrap();
    assert_engines_agree(&ps, 0.014, "r", "frame_0040 at cell r");
}

#[test]
fn full_grid_engines_refuse_above_the_memory_limit() {
    let _serial = serial();
    let ball = lattice_ball(Vec3::ZERO, 8.0 * R, R);
    let p = params(R, "r/2");
    let limits = Limits {
        max_memory: 100 << 10,
    };
    for engine in [Engine::FullGather, Engine::Scatter] {
        let e = match reconstruct_with(&ball, &p, engine, &limits) {
            Ok(_) => panic!("{engine:?} ran above the limit"),
            Err(e) => format!("{e:#}"),
        };
        assert!(e.contains("--max-memory") && e.contains("MB"), "{e}");
    }
    // The narrow band's memory follows the surface: no grid-sized plan to refuse.
    assert!(reconstruct_with(&ball, &p, Engine::NarrowBand, &limits).is_ok());
}

#[test]
fn memory_follows_the_cell_and_the_narrow_band_needs_least() {
    let _serial = serial();
    assert!(splash::memory::counting(), "the counting allocator is off");
    let ps = splash::io::read_particles(&fixture("frame_0040.ply"), None).unwrap();
    let heap = |cell: &str, engine| {
        let s = reconstruct(&ps, &params(0.014, cell), engine)
            .unwrap()
            .stats;
        // Every stage that ran holds something; the peak is the largest stage's.
        assert!(s.stage_heap.scalar_field > 0 && s.stage_heap.triangulation > 0);
        assert_eq!(s.heap_peak, s.stage_heap.max());
        assert!(s.peak_rss as usize > s.heap_peak);
        s.heap_peak
    };
    let mut at_half = Vec::new();
    for engine in [Engine::NarrowBand, Engine::FullGather, Engine::Scatter] {
        let (r, r2) = (heap("r", engine), heap("r/2", engine));
        assert!(r2 > 2 * r, "{engine:?}: {r} bytes at r, {r2} at r/2");
        at_half.push(r2);
    }
    let [band, gather, scatter] = at_half[..] else {
        unreachable!()
    };
    assert!(
        band < gather && gather < scatter,
        "{band} {gather} {scatter}"
    );
    // The estimate that --max-memory checks covers the grid; the mesh comes on top.
    let p = params(0.014, "r/2");
    let grid = Grid::around(&ps, p.cell, p.support).unwrap();
    for (engine, measured) in [(Engine::FullGather, gather), (Engine::Scatter, scatter)] {
        let need = needed_bytes(engine, &grid, ps.len()).unwrap() as f64;
        let ratio = measured as f64 / need;
        assert!(
            (0.9..1.6).contains(&ratio),
            "{engine:?}: measured/estimate {ratio}"
        );
    }
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("splash-report-{}-{name}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

/// Raw little-endian f32 triples.
fn write_raw(path: &Path, points: &[Vec3]) {
    let bytes: Vec<u8> = points
        .iter()
        .flat_map(|p| p.to_array())
        .flat_map(f32::to_le_bytes)
        .collect();
    fs::write(path, bytes).unwrap();
}

fn splash(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_splash"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn recon_report_counts_match_the_ball_and_its_mesh() {
    let _serial = serial();
    let dir = temp_dir("recon");
    let centre = Vec3::new(0.31, -0.2, 0.45);
    let ball = lattice_ball(centre, 0.06, R);
    let input = dir.join("ball_0001.bin");
    write_raw(&input, &ball);
    let mesh = dir.join("ball.obj");
    let s = |p: &Path| p.to_str().unwrap().to_string();
    for ext in ["json", "csv", "md"] {
        let report = dir.join(format!("report.{ext}"));
        let (ok, _, err) = splash(&[
            "recon",
            &s(&input),
            "--spacing",
            "0.01",
            "--cell",
            "r",
            "-o",
            &s(&mesh),
            "--report",
            &s(&report),
            "-q",
        ]);
        assert!(ok, "{err}");
        assert!(report.exists(), "no .{ext} report");
    }
    let report: Value =
        serde_json::from_str(&fs::read_to_string(dir.join("report.json")).unwrap()).unwrap();
    let frame = &report["frames"][0];
    assert_eq!(report["frames"].as_array().unwrap().len(), 1);
    assert_eq!(frame["particles"], ball.len() as f64);
    // The grid: vertices k·cell within the particles' box widened by the support 4r.
    let (lo, hi) = ball
        .iter()
        .fold((Vec3::MAX, Vec3::MIN), |(a, b), &p| (a.min(p), b.max(p)));
    for (axis, key) in ["grid_res_x", "grid_res_y", "grid_res_z"]
        .iter()
        .enumerate()
    {
        // In the units the code uses: r and 4r as f32, the division in f64. (The lattice's
        // coordinates fall on grid vertices, so the rounding decides.)
        let (cell, support) = (f64::from(R), f64::from(4.0 * R));
        let first = ((f64::from(lo[axis]) - support) / cell).ceil();
        let last = ((f64::from(hi[axis]) + support) / cell).floor();
        assert_eq!(frame[key], last - first + 1.0, "{key}");
    }
    // Triangles and vertices as written.
    let obj = fs::read_to_string(&mesh).unwrap();
    let faces = obj.lines().filter(|l| l.starts_with("f ")).count();
    let vertices = obj.lines().filter(|l| l.starts_with("v ")).count();
    assert!(faces > 0);
    assert_eq!(frame["triangles"], faces as f64);
    assert_eq!(frame["output_vertices"], vertices as f64);
    // A ball's surface particles are a shell: some but not all.
    let ratio = frame["surface_particle_ratio"].as_f64().unwrap();
    assert!(ratio > 0.1 && ratio < 0.9, "{ratio}");
    assert!(frame["heap_peak"].as_f64().unwrap() > 0.0);
    assert!(frame["t_scalar_field"].as_f64().unwrap() > 0.0);
    // The averages of one frame are the frame; the report states the machine, build, config.
    assert_eq!(report["average"]["triangles"], faces as f64);
    assert!(report["machine"]["cores"].as_u64().unwrap() >= 1);
    assert_eq!(report["build"]["version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(report["config"]["cell"], "r");
    assert_eq!(report["config"]["field"]["support"], "4r");
    let csv = fs::read_to_string(dir.join("report.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().filter(|l| !l.starts_with('#')).collect();
    assert_eq!(rows.len(), 3, "header, frame, average:\n{csv}");
    assert!(rows[2].contains(",average,"), "{csv}");
    let md = fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(
        md.contains("**average**") && md.contains("| t_sf [s] |"),
        "{md}"
    );
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bench_prints_the_tables_and_na_above_the_memory_limit() {
    let _serial = serial();
    let dir = temp_dir("bench");
    let scene = dir.join("balls");
    fs::create_dir_all(&scene).unwrap();
    for k in 0..2 {
        let centre = Vec3::new(0.1 * k as f32, 0.0, 0.0);
        write_raw(
            &scene.join(format!("f_{k}.bin")),
            &lattice_ball(centre, 0.05, R),
        );
    }
    let json = dir.join("bench.json");
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let (ok, out, err) = splash(&[
        "bench",
        &s(&scene),
        "--spacing",
        "0.01",
        "--cell",
        "r",
        "--cell",
        "r/2",
        "--threads",
        "1,2",
        "--json",
        &s(&json),
        "--max-memory",
        "2M",
        "-q",
    ]);
    assert!(ok, "{err}");
    for heading in [
        "Table 1 shape",
        "Table 3/4 shape: balls, cell size r.",
        "Table 3/4 shape: balls, cell size r/2.",
        "Table 5/6 shape: cell size r/2.",
    ] {
        assert!(out.contains(heading), "no '{heading}' in\n{out}");
    }
    for row in ["| scatter |", "| Z-index-2 threads |", "| our-1 thread |"] {
        assert!(out.contains(row), "no '{row}' in\n{out}");
    }
    // At r/2 the scatter's sums over the full grid exceed 2 MiB: NA with the reason.
    let r2 = &out[out.find("cell size r/2.").unwrap()..];
    assert!(
        r2.lines()
            .any(|l| l.starts_with("| scatter | NA") && l.contains("--max-memory")),
        "{r2}"
    );
    let records: Value = serde_json::from_str(&fs::read_to_string(&json).unwrap()).unwrap();
    // 2 frames × 2 cells × (scatter + 2 full gathers + 2 narrow bands).
    assert_eq!(records["runs"].as_array().unwrap().len(), 20);
    fs::remove_dir_all(&dir).unwrap();
}
