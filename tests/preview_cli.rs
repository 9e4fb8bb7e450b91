//! `splash preview` end to end: a sequence of PNGs with the farm options, and clear errors.

mod common;

use std::process::{Command, Output};

use common::{TempDir, finish, lattice_ball};
use glam::Vec3;

fn splash(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_splash"))
        .arg("preview")
        .args(args)
        .output()
        .unwrap()
}

fn ply(points: &[Vec3]) -> Vec<u8> {
    let mut out = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\nend_header\n",
        points.len()
    )
    .into_bytes();
    for p in points {
        for c in p.to_array() {
            out.extend(c.to_le_bytes());
        }
    }
    out
}

fn png_size(path: &std::path::Path) -> (u32, u32) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    let be = |i: usize| u32::from_be_bytes(bytes[i..i + 4].try_into().unwrap());
    (be(16), be(20))
}

#[test]
fn a_sharded_sequence_gives_one_png_per_frame() {
    let dir = TempDir::new("preview-seq");
    for (k, x) in [(1, 0.0), (2, 0.02), (3, 0.04)] {
        let points = lattice_ball(Vec3::new(x, 0.0, 0.0), 0.05, 0.01);
        dir.file(&format!("sim/f_{k}.ply"), ply(&points));
    }
    let sim = dir.path("sim").display().to_string();
    let out = dir.out_dir("png");
    let report = dir.path("report.json");
    for shard in ["1/2", "2/2"] {
        let run = splash(&[
            &sim,
            "--spacing",
            "0.01",
            "--size",
            "48x32",
            "--shard",
            shard,
            "--threads",
            "3",
            "--report",
            report.to_str().unwrap(),
            "-o",
            &out,
        ]);
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
    }
    // The report gives the workers asked for.
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(report).unwrap()).unwrap();
    assert_eq!(report["threads"], 3);
    assert_eq!(
        common::entries(&dir.path("png")),
        ["f_0001.png", "f_0002.png", "f_0003.png"]
    );
    assert_eq!(png_size(&dir.path("png/f_0002.png")), (48, 32));
    // Resumed: nothing left to do.
    let run = splash(&[
        &sim,
        "--spacing",
        "0.01",
        "--size",
        "48x32",
        "--skip-existing",
        "-o",
        &out,
    ]);
    let log = String::from_utf8_lossy(&run.stderr);
    assert!(
        run.status.success() && log.contains("0 frames written, 3 found complete"),
        "{log}"
    );
}

#[test]
fn json_logs_of_a_sequence_are_one_object_per_line() {
    let dir = TempDir::new("preview-json");
    for k in [1, 2, 3] {
        let points = lattice_ball(Vec3::new(0.02 * k as f32, 0.0, 0.0), 0.05, 0.01);
        dir.file(&format!("sim/f_{k}.ply"), ply(&points));
    }
    dir.file(
        "sim/f_4.ply",
        "ply\nformat ascii 1.0\nelement vertex 5\nend_header\n",
    );
    let sim = dir.path("sim").display().to_string();
    let out = dir.out_dir("png");
    let base = [
        sim.as_str(),
        "--spacing",
        "0.01",
        "--size",
        "40x30",
        "-o",
        &out,
        "--log-format",
        "json",
    ];
    let run = |extra: &[&str]| {
        let mut args = base.to_vec();
        args.extend(extra);
        let output = splash(&args);
        finish(format!("splash preview {}", args.join(" ")), output)
    };
    // Frames 1-3 and a broken frame 4: the same events as recon's, in the same shapes.
    let first = run(&["--frames", "1-4,9"]).failed();
    let start = &first.events("start")[0];
    assert_eq!((start.get("selected"), start.get("to_do")), ("4", "4"));
    let warnings = first.events("warning");
    assert!(
        warnings
            .iter()
            .any(|w| w.get("message").contains("1 frames of --frames")),
        "{}",
        first.stderr
    );
    assert_eq!(first.frames(), [1, 2, 3, 4]);
    let frames = first.events("frame");
    for f in &frames[..3] {
        assert_eq!(f.get("status"), "\"ok\"");
        assert!(
            f.get("particles").parse::<usize>().unwrap() > 100,
            "{}",
            f.0
        );
        assert!(f.get("hits").parse::<u64>().unwrap() > 0, "{}", f.0);
        for key in ["seconds", "build_ms", "render_ms", "rays_per_second"] {
            assert!(f.get(key).parse::<f64>().unwrap() >= 0.0, "{key}: {}", f.0);
        }
        assert!(f.get("output").ends_with(".png\""), "{}", f.0);
    }
    assert_eq!(frames[3].get("status"), "\"error\"");
    assert!(
        frames[3].get("error").contains("f_4.ply"),
        "{}",
        frames[3].0
    );
    let summary = &first.events("summary")[0];
    assert_eq!(summary.get("written"), "3");
    assert_eq!(summary.get("ok"), "false");
    assert!(summary.get("failed").contains("f_4.ply"), "{}", summary.0);
    // Resumed with --skip-existing: the three images are found, the broken frame fails again.
    let second = run(&["--skip-existing", "--frames", "1-4"]).failed();
    let start = &second.events("start")[0];
    assert_eq!((start.get("skipped"), start.get("to_do")), ("3", "1"));
    assert_eq!(second.frames(), [4]);
    // The spacing estimate is an event too.
    let mut args = vec![sim.as_str(), "--size", "40x30", "-o", &out];
    args.extend(["--frames", "1", "--log-format", "json"]);
    let third = finish("estimate".into(), splash(&args)).ok();
    assert_eq!(third.events("spacing").len(), 1);
    assert_eq!(third.events("summary")[0].get("ok"), "true");
}

#[test]
fn bad_arguments_are_clear_errors() {
    let dir = TempDir::new("preview-bad");
    let frame = dir.file("f_1.ply", ply(&lattice_ball(Vec3::ZERO, 0.04, 0.01)));
    let frame = frame.display().to_string();
    for (args, expected) in [
        (vec!["--size", "100000x100000"], "too large"),
        (vec!["--size", "0x10"], "at least 1"),
        (vec!["--size", "big"], "WIDTHxHEIGHT"),
        (vec!["--fov", "0"], "between 0 and 180"),
        (vec!["--camera", "0,0,nan"], "finite"),
        (vec!["--camera", "1,1,1", "--look-at", "1,1,1"], "coincide"),
        (vec!["--look-at", "1,1,1"], "needs --camera"),
        (vec!["--colour", "#12"], "colour"),
        (vec!["--bvh", "octree"], "unknown BVH"),
        (vec!["-o", "x.jpg"], ".png"),
    ] {
        let mut all = vec![frame.as_str(), "--spacing", "0.01"];
        all.extend(&args);
        let run = splash(&all);
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(!run.status.success(), "{args:?} succeeded");
        assert!(err.contains(expected), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    let missing = dir.path("f_2.ply").display().to_string();
    let out = dir.path("m.png").display().to_string();
    let run = splash(&[
        &missing,
        "--spacing",
        "0.01",
        "--camera",
        "0,0,1",
        "--look-at",
        "0,0,0",
        "-o",
        &out,
    ]);
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success() && err.contains("f_2.ply"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}
