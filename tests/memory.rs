//! The memory limit end to end: a frame that would need more than `--max-memory` fails alone,
//! with an error that names the file and the figures, for every engine; nothing aborts.

mod common;

use std::fs;
use std::process::{Command, Output};

use common::{TempDir, entries, fixture, lattice_ball};
use glam::Vec3;

const ENGINES: [&str; 4] = ["narrow-band", "full-gather", "scatter", "slices"];

/// Runs `splash recon` with `args`; a run killed by a signal (an aborted allocation) or that
/// panicked fails the test. Returns the exit code and stderr.
fn recon(args: &[&dyn AsRef<std::ffi::OsStr>]) -> (i32, String) {
    let Output { status, stderr, .. } = Command::new(env!("CARGO_BIN_EXE_splash"))
        .arg("recon")
        .args(args.iter().map(|a| a.as_ref()))
        .output()
        .expect("cannot start splash");
    let stderr = String::from_utf8_lossy(&stderr).into_owned();
    let code = status
        .code()
        .unwrap_or_else(|| panic!("splash was killed ({status}); stderr:\n{stderr}"));
    assert!(!stderr.contains("panicked"), "{stderr}");
    (code, stderr)
}

fn csv(points: &[Vec3]) -> String {
    let mut s = String::from("x,y,z\n");
    for p in points {
        s += &format!("{},{},{}\n", p.x, p.y, p.z);
    }
    s
}

/// A cell of 0.0001 at r = 0.014 (r/140) on frame_0040 once aborted the process at 2.5 GB
/// with no file name; the frame after it was never attempted.
#[test]
fn a_frame_above_the_memory_limit_fails_alone_for_every_engine() {
    let dir = TempDir::new("mem-limit");
    let big = dir.path("in/frame_0040.ply");
    fs::create_dir_all(big.parent().unwrap()).unwrap();
    fs::copy(fixture("frame_0040.ply"), &big).unwrap();
    // The good frame: empty, so that it fits at this cell too (one particle at r/140 takes a
    // band of 350 k bricks).
    let good = dir.file("in/frame_0041.csv", "x,y,z\n");
    for engine in ENGINES {
        let out = dir.path(engine);
        let (code, err) = recon(&[
            &big,
            &good,
            &"--spacing",
            &"0.014",
            &"--cell",
            &"0.0001",
            &"--engine",
            &engine,
            &"--max-memory",
            &"4G",
            &"-o",
            &dir.out_dir(engine),
        ]);
        assert_eq!(code, 1, "{engine}: {err}");
        assert_eq!(entries(&out), ["frame_0041.obj"], "{engine}: {err}");
        let summary = &err[err.find("1 of 2 frames failed").expect(&err)..];
        let line = format!(
            "{}: reconstruction failed: the {engine} engine would need about",
            big.display()
        );
        assert!(summary.contains(&line), "{engine}: no '{line}' in\n{err}");
        for part in [
            "GB for ",
            "above the memory limit of 4.29 GB (--max-memory)",
            "larger cell",
            "raise --max-memory",
        ] {
            assert!(summary.contains(part), "{engine}: no '{part}' in\n{err}");
        }
    }
    // Under the default limit (a fraction of the memory available) as well.
    let (code, err) = recon(&[
        &big,
        &"--spacing",
        &"0.014",
        &"--cell",
        &"0.0001",
        &"-o",
        &dir.out_dir("default"),
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("the narrow-band engine would need about 175"),
        "{err}"
    );
}

/// Two balls 10⁴ units apart: the full grid between them is refused before it is allocated,
/// the engines whose memory follows the surface mesh both balls; under a limit of 32 KiB
/// every engine refuses.
#[test]
fn particles_spread_over_a_huge_box_are_refused_or_meshed_never_aborted() {
    let dir = TempDir::new("mem-spread");
    let mut points = lattice_ball(Vec3::ZERO, 3.0, 1.0);
    points.extend(lattice_ball(Vec3::splat(1e4), 3.0, 1.0));
    let input = dir.file("in/spread.csv", csv(&points));
    for engine in ENGINES {
        let out = dir.path(engine);
        let (code, err) = recon(&[
            &input,
            &"--spacing",
            &"1",
            &"--engine",
            &engine,
            &"-o",
            &dir.out_dir(engine),
        ]);
        if engine.starts_with("full") || engine == "scatter" {
            assert_eq!(code, 1, "{engine}: {err}");
            assert!(err.contains("its full grid of "), "{engine}: {err}");
            assert!(entries(&out).is_empty(), "{engine}");
        } else {
            assert_eq!(code, 0, "{engine}: {err}");
            assert_eq!(entries(&out), ["spread.obj"], "{engine}");
        }
        let (code, err) = recon(&[
            &input,
            &"--spacing",
            &"1",
            &"--engine",
            &engine,
            &"--max-memory",
            &"32K",
            &"-o",
            &dir.out_dir("tight"),
        ]);
        assert_eq!(code, 1, "{engine}: {err}");
        assert!(
            err.contains("above the memory limit of 33 kB (--max-memory)"),
            "{engine}: {err}"
        );
    }
}

/// A limit between what the engines need on frame_0040 at r/2 (narrow band about 20 MB,
/// full gather 36 MB, slices 30 MB, scatter 184 MB): each meshes or refuses, none aborts.
#[test]
fn a_tight_limit_meshes_or_refuses() {
    let dir = TempDir::new("mem-tight");
    let input = fixture("frame_0040.ply");
    for engine in ENGINES {
        let (code, err) = recon(&[
            &input,
            &"--spacing",
            &"0.014",
            &"--engine",
            &engine,
            &"--max-memory",
            &"50M",
            &"-o",
            &dir.out_dir(engine),
        ]);
        let written = entries(&dir.path(engine)) == ["frame_0040.obj"];
        match engine {
            "narrow-band" | "full-gather" | "slices" => {
                assert!(code == 0 && written, "{engine}: {err}")
            }
            _ => {
                assert!(code == 1 && !written, "{engine}: {err}");
                assert!(
                    err.contains("above the memory limit of 52.4 MB"),
                    "{engine}: {err}"
                );
            }
        }
    }
}
