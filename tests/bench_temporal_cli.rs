//! `splash bench temporal` on real frames (dense-dambreak 120–124 from `../shared`, skipped
//! without it): a row per variant in the jitter table, and the carried figure split by part
//! (body, pieces, droplets) with shares of the vertices that add up to the whole.

mod common;

use std::process::Command;

use common::{TempDir, finish, lattice_ball, shared_data};
use glam::Vec3;

#[test]
fn bench_temporal_splits_the_carried_jitter_by_part() {
    let Some(dir) = shared_data("dense-dambreak") else {
        return;
    };
    let output = Command::new(env!("CARGO_BIN_EXE_splash"))
        .args(["bench", "temporal", dir.to_str().unwrap()])
        .args(["--frames", "120-124", "--spacing", "0.04", "--threads", "2"])
        .args(["--peer", "none"])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    finish("splash bench temporal".into(), output).ok();
    let (jitter, parts) = stdout
        .split_once("Carried jitter by part")
        .unwrap_or_else(|| panic!("no table by part in:\n{stdout}"));
    let names = |rows: &[Vec<String>]| rows.iter().map(|r| r[0].clone()).collect::<Vec<_>>();
    let (jitter, parts) = (rows(jitter), rows(parts));
    assert_eq!(names(&jitter), ["raw", "single-frame", "temporal"]);
    assert_eq!(names(&parts), names(&jitter));
    for row in &parts {
        // "0.0127 (84.5 %)": a finite RMS and a share; the shares make the whole.
        let mut total = 0.0;
        for cell in &row[1..] {
            let (rms, share) = cell.split_once(" (").expect(cell);
            let rms: f64 = rms.parse().expect(cell);
            assert!(rms.is_finite() && rms >= 0.0, "{cell}");
            total += share.trim_end_matches(" %)").parse::<f64>().expect(cell);
        }
        assert_eq!(row.len(), 4, "{row:?}");
        assert!(
            (total - 100.0).abs() < 0.2,
            "{row:?}: shares add up to {total} %"
        );
    }
}

/// The rows of the Markdown table(s) in `table`, cells trimmed, the heading left out.
fn rows(table: &str) -> Vec<Vec<String>> {
    table
        .lines()
        .filter(|l| l.starts_with("| ") && !l.starts_with("| mesh"))
        .map(|l| {
            l.trim_matches('|')
                .split('|')
                .map(|c| c.trim().to_string())
                .collect()
        })
        .collect()
}

/// The carried figure of each row in `stdout`'s first table, by name.
fn carried(stdout: &str) -> Vec<(String, f64)> {
    let (first, _) = stdout
        .split_once("Carried jitter by part")
        .unwrap_or((stdout, ""));
    rows(first)
        .into_iter()
        .map(|r| (r[0].clone(), r[2].parse().expect(&r[2])))
        .collect()
}

#[test]
fn a_rigid_step_of_whole_cells_reads_no_carried_jitter_and_a_fractional_one_does() {
    let dir = TempDir::new("rigid");
    // A lattice ball of spacing 0.1 (the lattice points within √30 spacings of its centre).
    let text: String = lattice_ball(Vec3::ZERO, 0.55, 0.1)
        .iter()
        .map(|p| format!("{},{},{}\n", p.x, p.y, p.z))
        .collect();
    let input = dir.file("ball.csv", format!("x,y,z\n{text}"));
    let bench = |step: &str| {
        let output = Command::new(env!("CARGO_BIN_EXE_splash"))
            .args(["bench", "temporal", input.to_str().unwrap()])
            .args(["--spacing", "0.1", "--threads", "2", "--peer", "none"])
            .args(["--rigid-step", step, "--rigid-frames", "4"])
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
        finish(format!("splash bench temporal --rigid-step {step}"), output).ok();
        carried(&stdout)
    };
    // Two cells of r/2 a frame: every mesh is its predecessor moved, whatever made it.
    let whole = bench("2,0,-1");
    assert_eq!(whole.len(), 3, "{whole:?}");
    for (name, c) in &whole {
        assert!(
            *c < 1e-4,
            "{name}: carried {c} r for a rigid step of whole cells"
        );
    }
    // A fractional step cuts the surface anew each frame.
    let raw = bench("0.37,0.23,0.29")[0].clone();
    assert!(raw.0 == "raw" && raw.1 > 1e-3, "{raw:?}");
    let bad = Command::new(env!("CARGO_BIN_EXE_splash"))
        .args([
            "bench",
            "temporal",
            input.to_str().unwrap(),
            "--rigid-step",
            "1,2",
        ])
        .output()
        .unwrap();
    finish("splash bench temporal --rigid-step 1,2".into(), bad)
        .failed()
        .has("--rigid-step '1,2' must be three");
}
