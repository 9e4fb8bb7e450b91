//! The command line runs the Marching Slices engine and reports its blocks.

mod common;

use common::{TempDir, fixture};

#[test]
fn the_command_line_runs_slices_and_reports_the_blocks() {
    let dir = TempDir::new("slices-cli");
    let report = dir.path("report.json");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_splash"))
        .args(["recon", fixture("frame_0010.ply").to_str().unwrap()])
        .args(["--spacing", "0.014", "--cell", "r", "--engine", "slices"])
        .args(["--block", "16", "-v", "-o"])
        .arg(dir.path("mesh.obj"))
        .arg("--report")
        .arg(&report)
        .output()
        .unwrap();
    let log =
        String::from_utf8_lossy(&out.stderr).to_string() + &String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{log}");
    assert!(
        log.contains("blocks: render memory") && log.contains("slices"),
        "{log}"
    );
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    let frame = &json["frames"][0];
    for key in [
        "slices_blocks",
        "slices_peak_slices",
        "slices_render_bytes_max",
        "slices_cache_bytes_max",
        "slices_in_flight_peak",
    ] {
        assert!(frame[key].as_f64().unwrap() > 0.0, "{key}: {frame}");
    }
    let bad = std::process::Command::new(env!("CARGO_BIN_EXE_splash"))
        .args(["config", "show", "--block", "0"])
        .output()
        .unwrap();
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("slices.block"));
}
