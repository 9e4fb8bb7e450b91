//! Output that used to be silently wrong now comes with a reason (issue 14, item 5), an
//! unwritable output directory fails before any work (item 8), and `--log-format json` gives
//! nothing but JSON lines on stderr (item 9).

mod common;

use std::fmt::Write as _;
use std::fs;
use std::process::Command;

use common::{TempDir, lattice_ball};
use glam::Vec3;

const R: f32 = 0.014;

fn csv(points: &[Vec3]) -> String {
    let mut out = "x,y,z\n".to_owned();
    for p in points {
        writeln!(out, "{},{},{}", p.x, p.y, p.z).unwrap();
    }
    out
}

fn ball() -> Vec<Vec3> {
    lattice_ball(Vec3::new(0.3, -0.2, 0.4), 0.1, R)
}

/// Exit code and stderr of `splash recon args...`.
fn recon(args: &[&str]) -> (i32, String) {
    let output = Command::new(env!("CARGO_BIN_EXE_splash"))
        .arg("recon")
        .args(args)
        .output()
        .expect("cannot start splash");
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(!stderr.contains("panicked"), "{args:?} panicked:\n{stderr}");
    (output.status.code().expect("killed by a signal"), stderr)
}

fn faces(obj: &std::path::Path) -> usize {
    fs::read_to_string(obj)
        .unwrap()
        .lines()
        .filter(|l| l.starts_with("f "))
        .count()
}

#[test]
fn coincident_particles_give_a_sphere() {
    let dir = TempDir::new("coincident");
    for n in [20, 30, 100] {
        let input = dir.file(
            &format!("p{n}.csv"),
            csv(&vec![Vec3::new(1.0, 2.0, 3.0); n]),
        );
        let out = dir.path(&format!("p{n}.obj"));
        let (code, stderr) = recon(&[
            input.to_str().unwrap(),
            "--spacing",
            "0.014",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert_eq!(code, 0, "{stderr}");
        assert!(
            faces(&out) > 50,
            "{n} particles at one point gave {} triangles",
            faces(&out)
        );
    }
}

#[test]
fn spacings_beyond_f32_are_refused() {
    let dir = TempDir::new("spacing-range");
    let input = dir.file("ball.csv", csv(&ball()));
    let (code, stderr) = recon(&[input.to_str().unwrap(), "--spacing", "1e30"]);
    assert_ne!(code, 0);
    assert!(stderr.contains("spacing 1e30 is outside"), "{stderr}");
    // Scaled by 1e-20 the estimated spacing is 1.4e-22: refused, not an empty mesh.
    let tiny: Vec<Vec3> = ball().iter().map(|&p| p * 1e-20).collect();
    let input = dir.file("tiny.csv", csv(&tiny));
    let (code, stderr) = recon(&[input.to_str().unwrap()]);
    assert_ne!(code, 0);
    assert!(stderr.contains("is outside 1e-9 to 1e9"), "{stderr}");
    assert!(!dir.path("tiny_surface.obj").exists());
}

#[test]
fn coordinates_beyond_f32_resolution_are_refused() {
    let dir = TempDir::new("far");
    let far: Vec<Vec3> = ball().iter().map(|&p| p + Vec3::X * 1e5).collect();
    let input = dir.file("far.csv", csv(&far));
    let (code, stderr) = recon(&[input.to_str().unwrap(), "--spacing", "0.014"]);
    assert_ne!(code, 0);
    assert!(
        stderr.contains("are beyond f32's resolution for cell 0.007"),
        "{stderr}"
    );
    // Near the origin the same ball is fine.
    let input = dir.file("near.csv", csv(&ball()));
    let (code, stderr) = recon(&[input.to_str().unwrap(), "--spacing", "0.014"]);
    assert_eq!(code, 0, "{stderr}");
    assert!(!stderr.contains("warning"), "{stderr}");
}

#[test]
fn a_spacing_far_from_the_estimate_is_warned_about() {
    let dir = TempDir::new("estimate");
    let input = dir.file("ball.csv", csv(&ball()));
    let input = input.to_str().unwrap();
    for (spacing, words) in [
        ("0.05", "× the 0.014"),
        ("0.005", "× the 0.014"),
        ("1", "less than one cell"),
    ] {
        let (code, stderr) = recon(&[input, "--spacing", spacing]);
        assert_eq!(code, 0, "{stderr}");
        let warning = stderr
            .lines()
            .find(|l| l.starts_with("warning: "))
            .unwrap_or_else(|| panic!("--spacing {spacing}: no warning in\n{stderr}"));
        assert!(warning.contains(words), "{warning}");
    }
    let (_, stderr) = recon(&[input, "--spacing", "0.014"]);
    assert!(!stderr.contains("warning"), "{stderr}");
}

#[test]
fn an_output_directory_that_cannot_be_created_fails_first() {
    let dir = TempDir::new("no-dir");
    let input = dir.file("ball.csv", csv(&ball()));
    dir.file("file", "a regular file");
    let out = format!("{}/out/", dir.path("file").display());
    let (code, stderr) = recon(&[input.to_str().unwrap(), "-o", &out, "--spacing", "0.014"]);
    assert_ne!(code, 0);
    assert!(
        stderr.contains("cannot create the output directory") && stderr.contains("file/out"),
        "{stderr}"
    );
    // Said once, before any frame.
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    for out in ["/proc/splash-no-such-dir/", "/proc/x.obj"] {
        let (code, stderr) = recon(&[input.to_str().unwrap(), "-o", out, "--spacing", "0.014"]);
        assert_ne!(code, 0);
        assert!(stderr.contains("no frame was reconstructed"), "{stderr}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
    }
}

#[test]
fn a_read_only_output_directory_fails_first() {
    use std::os::unix::fs::PermissionsExt;
    let dir = TempDir::new("read-only");
    let input = dir.file("ball.csv", csv(&ball()));
    let out = dir.path("out");
    fs::create_dir(&out).unwrap();
    fs::set_permissions(&out, fs::Permissions::from_mode(0o555)).unwrap();
    if fs::write(out.join("probe"), "").is_ok() {
        // Root writes anyway.
        eprintln!("skipped: permissions do not stop this user (root?)");
        return;
    }
    let (code, stderr) = recon(&[
        input.to_str().unwrap(),
        "-o",
        &format!("{}/", out.display()),
        "--spacing",
        "0.014",
    ]);
    fs::set_permissions(&out, fs::Permissions::from_mode(0o755)).unwrap();
    assert_ne!(code, 0);
    assert!(
        stderr.contains("cannot write in the output directory"),
        "{stderr}"
    );
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
}

#[test]
fn json_logs_are_json_lines_only() {
    let dir = TempDir::new("json");
    let ball = dir.file("seq/f_1.csv", csv(&ball()));
    dir.file("seq/f_2.csv", "x,y,z\n1,2\n");
    dir.file("seq/notes.txt", "not a frame");
    let seq = dir.path("seq");
    let (seq, ball) = (seq.to_str().unwrap(), ball.to_str().unwrap());
    let file = dir.file("file", "");
    let under_file = format!("{}/out/", file.display());
    let out = dir.out_dir("out");
    let config = dir.file("bad.toml", "cell = \"r/0\"\n");
    let runs: Vec<(Vec<&str>, &str)> = vec![
        // A skipped file, the spacing estimate, a failed frame, the summary.
        (vec![seq, "-o", &out], "summary"),
        // The spacing warning.
        (vec![ball, "--spacing", "0.05", "-o", &out], "summary"),
        (vec![ball, "--spacing", "abc"], "error"),
        (vec![ball, "--bogus"], "error"),
        (vec![ball, "--cell", "9r", "--spacing", "0.014"], "error"),
        (vec![ball, "--config", config.to_str().unwrap()], "error"),
        (vec![ball, "--frames", "7", "-o", &out], "error"),
        (vec![ball, "-o", &under_file], "error"),
        (vec!["/nonexistent/dir/"], "summary"),
        (vec![], "error"),
    ];
    for (mut args, last_event) in runs {
        args.extend(["--log-format", "json"]);
        let (code, stderr) = recon(&args);
        let events: Vec<String> = stderr
            .lines()
            .map(|line| {
                let value: serde_json::Value = serde_json::from_str(line)
                    .unwrap_or_else(|e| panic!("{args:?}: not JSON ({e}): {line}\n{stderr}"));
                value["event"]
                    .as_str()
                    .unwrap_or_else(|| panic!("{args:?}: no event in {line}"))
                    .to_owned()
            })
            .collect();
        assert_eq!(
            events.last().map(String::as_str),
            Some(last_event),
            "{args:?}:\n{stderr}"
        );
        if last_event == "error" {
            assert_ne!(code, 0, "{args:?}:\n{stderr}");
        }
    }
    // `--log-format=json` counts as well.
    let (_, stderr) = recon(&[ball, "--spacing", "0.05", "--log-format=json", "-o", &out]);
    assert!(
        stderr.lines().all(|l| l.starts_with("{\"event\":")),
        "{stderr}"
    );
}

/// A missing input names the operating system's reason once per report of it, in text and
/// JSON logs alike (it used to come twice: in the library's message and again as its source).
#[test]
fn a_missing_file_gives_its_reason_once() {
    let dir = TempDir::new("missing");
    let missing = dir.path("nothing.ply");
    let reason = fs::File::open(&missing).unwrap_err().to_string();
    let out = dir.path("out.obj");
    for log in ["plain", "json"] {
        let (code, stderr) = recon(&[
            missing.to_str().unwrap(),
            "--spacing",
            "0.05",
            "--log-format",
            log,
            "-o",
            out.to_str().unwrap(),
        ]);
        assert_ne!(code, 0, "{stderr}");
        assert!(stderr.contains("nothing.ply"), "{stderr}");
        // Each line that reports the failure (the frame's, the summary's) says why once.
        let lines: Vec<&str> = stderr.lines().filter(|l| l.contains(&reason)).collect();
        assert!(!lines.is_empty(), "{log}: {stderr}");
        for line in lines {
            assert_eq!(line.matches(&reason).count(), 1, "{log}: {line}");
        }
    }
}
