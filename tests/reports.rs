//! `splash recon --report` and `splash bench` report the right counts and tables.

mod common;

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

use common::lattice_ball;
use glam::Vec3;
use serde_json::Value;

const R: f32 = 0.01;

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
            "--threads",
            "3",
            "-q",
        ]);
        assert!(ok, "{err}");
        assert!(report.exists(), "no .{ext} report");
    }
    let report: Value =
        serde_json::from_str(&fs::read_to_string(dir.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["threads_used"], 3, "the workers asked for");
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
    // The stages, post-processing (on by default) among them, add up to the total.
    let t = |key: &str| frame[key].as_f64().unwrap_or_else(|| panic!("no {key}"));
    assert!(t("t_post") > 0.0 && t("heap_post") > 0.0);
    let stages: f64 = [
        "t_read",
        "t_handler_array",
        "t_surface_particles",
        "t_band",
        "t_scalar_field",
        "t_triangulation",
        "t_post",
        "t_write",
    ]
    .iter()
    .map(|k| t(k))
    .sum();
    assert!(
        (stages - t("t_total")).abs() <= 1e-6 * t("t_total"),
        "{frame}"
    );
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
    assert!(
        rows[0].contains(",t_triangulation,t_post,t_write,"),
        "{csv}"
    );
    let md = fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(
        md.contains("**average**") && md.contains("| t_sf [s] |") && md.contains("| t_post [s] |"),
        "{md}"
    );
    // The JSON log's frame event has the stage times too; --raw runs no post-processing: its
    // time is 0 in the report and the log.
    for raw in [false, true] {
        let raw_report = dir.join("raw.json");
        let mut args = vec![
            "recon".to_string(),
            s(&input),
            "--spacing".into(),
            "0.01".into(),
            "--cell".into(),
            "r".into(),
            "-o".into(),
            s(&mesh),
            "--report".into(),
            s(&raw_report),
            "--log-format".into(),
            "json".into(),
        ];
        if raw {
            args.push("--raw".into());
        }
        let (ok, _, err) = splash(&args.iter().map(String::as_str).collect::<Vec<_>>());
        assert!(ok, "{err}");
        let event: Value = err
            .lines()
            .filter_map(|l| serde_json::from_str::<Value>(l).ok())
            .find(|e| e["event"] == "frame")
            .unwrap_or_else(|| panic!("no frame event: {err}"));
        let times = &event["times"];
        let t = |key: &str| times[key].as_f64().unwrap_or_else(|| panic!("{event}"));
        assert!(t("post") <= t("reconstruction"), "{event}");
        let sum = t("read") + t("reconstruction") + t("write");
        assert!(
            (sum - event["seconds"].as_f64().unwrap()).abs() < 0.0025,
            "{event}"
        );
        let report: Value =
            serde_json::from_str(&fs::read_to_string(&raw_report).unwrap()).unwrap();
        let post = report["frames"][0]["t_post"].as_f64().unwrap();
        assert_eq!(post == 0.0, raw, "{report}");
        assert_eq!(report["frames"][0]["heap_post"] == 0.0, raw, "{report}");
    }
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bench_prints_the_tables_and_na_above_the_memory_limit() {
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
