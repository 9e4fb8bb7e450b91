//! `splash bench slices`: Fig. 7 of Rosenberg & Birdwell 2008 in shape on the bundled frame,
//! the slices engine and its two baselines each a row with the same triangles and mesh, and
//! the table written to --markdown as printed.

mod common;

use std::fs;
use std::process::Command;

use common::{TempDir, finish, fixture, repository};

fn bench_slices(args: &[&str]) -> (common::Run, String) {
    let output = Command::new(env!("CARGO_BIN_EXE_splash"))
        .args([
            "bench",
            "slices",
            fixture("frame_0040.ply").to_str().unwrap(),
        ])
        .args(["--spacing", "0.014"])
        .args(args)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    (
        finish(format!("splash bench slices {}", args.join(" ")), output),
        stdout,
    )
}

#[test]
fn bench_slices_prints_fig_7_with_the_same_mesh_for_every_approach() {
    let dir = TempDir::new("bench-slices");
    let markdown = dir.path("fig7.md");
    let config = repository().join("configs/metaball.toml");
    let (run, stdout) = bench_slices(&[
        "--config",
        config.to_str().unwrap(),
        "--cell",
        "r",
        "--repeat",
        "1",
        "--markdown",
        markdown.to_str().unwrap(),
    ]);
    run.ok();
    assert!(stdout.contains("Fig. 7 (shape)"), "{stdout}");
    assert!(stdout.contains("field metaball, cell r"), "{stdout}");
    let header = stdout
        .lines()
        .find(|l| l.starts_with("| approach |"))
        .unwrap_or_else(|| panic!("no table:\n{stdout}"));
    let columns: Vec<&str> = header.split('|').map(str::trim).collect();
    for c in [
        "fps",
        "cubes/s",
        "tris/s",
        "render mem [MB]",
        "cache mem [MB]",
        "triangles",
        "mesh",
    ] {
        assert!(columns.contains(&c), "no column {c}: {header}");
    }
    let at = |name: &str| columns.iter().position(|c| *c == name).unwrap();
    let rows: Vec<Vec<&str>> = stdout
        .lines()
        .filter(|l| l.starts_with("| 1 ") || l.starts_with("| 2 ") || l.starts_with("| 3 "))
        .map(|l| l.split('|').map(str::trim).collect())
        .collect();
    assert_eq!(rows.len(), 3, "{stdout}");
    let triangles: Vec<&str> = rows.iter().map(|r| r[at("triangles")]).collect();
    assert!(triangles[0].parse::<usize>().unwrap() > 10_000, "{stdout}");
    assert!(triangles.iter().all(|t| *t == triangles[0]), "{stdout}");
    let meshes: Vec<&str> = rows.iter().map(|r| r[at("mesh")]).collect();
    assert_eq!(meshes, ["reference", "same", "same"], "{stdout}");
    for r in &rows {
        for c in ["fps", "render mem [MB]", "cache mem [MB]"] {
            assert!(r[at(c)].parse::<f64>().unwrap() > 0.0, "{c}: {stdout}");
        }
    }
    assert!(stdout.contains("slices vs (2):") && stdout.contains("slices vs (3):"));
    assert_eq!(fs::read_to_string(&markdown).unwrap(), stdout);
}

#[test]
fn bench_slices_refuses_zero_threads() {
    let (run, _) = bench_slices(&["--threads", "0"]);
    run.failed()
        .has("--threads and --repeat must be at least 1");
}
