//! The `splash` binary end to end: every input format and thread count gives the same mesh, bad
//! input is reported without writing anything, output names, replacement of existing meshes and
//! the spacing options.

mod common;

use std::ffi::OsString;
use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

use common::{TempDir, entries, fixture, lattice_ball};
use glam::Vec3;

/// Particle spacing of the test balls.
const R: f32 = 0.01;

/// A lattice ball of about 2 100 particles, off the origin so that coordinates have many digits.
fn ball() -> Vec<Vec3> {
    lattice_ball(Vec3::new(0.31, -0.2, 0.45), 0.08, R)
}

fn ply_binary(points: &[Vec3]) -> Vec<u8> {
    let mut out = format!(
        "ply\nformat binary_little_endian 1.0\ncomment cli test\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\nend_header\n",
        points.len()
    )
    .into_bytes();
    out.extend(raw(points));
    out
}

fn ply_ascii(points: &[Vec3]) -> String {
    let mut out = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\nend_header\n",
        points.len()
    );
    for p in points {
        // `{}` prints the shortest text that reads back as the same f32.
        writeln!(out, "{} {} {}", p.x, p.y, p.z).unwrap();
    }
    out
}

fn csv(points: &[Vec3], header: bool) -> String {
    let mut out = if header {
        "x,y,z\n".to_owned()
    } else {
        String::new()
    };
    for p in points {
        writeln!(out, "{},{},{}", p.x, p.y, p.z).unwrap();
    }
    out
}

fn raw(points: &[Vec3]) -> Vec<u8> {
    points
        .iter()
        .flat_map(|p| p.to_array())
        .flat_map(f32::to_le_bytes)
        .collect()
}

/// `points` as CSV with a header, the second particle (on line 3) replaced by `row`.
fn csv_with_row(points: &[Vec3], row: &str) -> String {
    let mut lines: Vec<String> = csv(points, true).lines().map(str::to_owned).collect();
    lines[2] = row.to_owned();
    lines.join("\n") + "\n"
}

/// What one run of the binary did.
struct Run {
    command: String,
    success: bool,
    stderr: String,
}

impl Run {
    fn assert_success(&self) -> &Self {
        assert!(
            self.success,
            "{} failed; stderr:\n{}",
            self.command, self.stderr
        );
        self
    }

    fn assert_failure(&self) -> &Self {
        assert!(
            !self.success,
            "{} succeeded; stderr:\n{}",
            self.command, self.stderr
        );
        self
    }

    fn assert_stderr_has(&self, expected: &str) -> &Self {
        assert!(
            self.stderr.contains(expected),
            "{}: no '{expected}' in stderr:\n{}",
            self.command,
            self.stderr
        );
        self
    }
}

/// Runs `splash` with `args`; a run killed by a signal or that panicked fails the test.
fn splash(args: &[OsString]) -> Run {
    let output = Command::new(env!("CARGO_BIN_EXE_splash"))
        .args(args)
        .output()
        .expect("cannot start splash");
    let command = format!(
        "splash {}",
        args.iter()
            .map(|a| a.to_string_lossy())
            .collect::<Vec<_>>()
            .join(" ")
    );
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(
        output.status.code().is_some(),
        "{command} was killed: {}; stderr:\n{stderr}",
        output.status
    );
    assert!(
        !stderr.contains("panicked"),
        "{command} panicked; stderr:\n{stderr}"
    );
    Run {
        command,
        success: output.status.success(),
        stderr,
    }
}

/// Something that goes on the command line: a `&str`, `String`, `PathBuf` or an array of `&str`.
trait Arg {
    fn push_to(&self, args: &mut Vec<OsString>);
}

impl Arg for str {
    fn push_to(&self, args: &mut Vec<OsString>) {
        args.push(self.into());
    }
}

impl Arg for String {
    fn push_to(&self, args: &mut Vec<OsString>) {
        args.push(self.into());
    }
}

impl Arg for PathBuf {
    fn push_to(&self, args: &mut Vec<OsString>) {
        args.push(self.into());
    }
}

impl<T: Arg + ?Sized> Arg for &T {
    fn push_to(&self, args: &mut Vec<OsString>) {
        (**self).push_to(args);
    }
}

impl Arg for Vec<&str> {
    fn push_to(&self, args: &mut Vec<OsString>) {
        args.extend(self.iter().map(OsString::from));
    }
}

impl<const N: usize> Arg for [&str; N] {
    fn push_to(&self, args: &mut Vec<OsString>) {
        args.extend(self.iter().map(OsString::from));
    }
}

/// `splash!["recon", path, SPACING]`: runs splash with the arguments.
macro_rules! splash {
    ($($arg:expr),* $(,)?) => {{
        let mut args: Vec<OsString> = Vec::new();
        $(Arg::push_to(&$arg, &mut args);)*
        splash(&args)
    }};
}

/// The spacing of the test balls and the cell size that keeps runs fast.
const SPACING: [&str; 4] = ["--spacing", "0.01", "--cell", "r"];

/// Vertex and triangle counts of a binary little-endian PLY mesh as splash writes it, after
/// checking the payload's size and every face's indices.
fn ply_mesh(path: &Path) -> (usize, usize) {
    let bytes = fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let end = b"end_header\n";
    let header_len = bytes
        .windows(end.len())
        .position(|w| w == end)
        .unwrap_or_else(|| panic!("{}: no end_header", path.display()))
        + end.len();
    let header = std::str::from_utf8(&bytes[..header_len]).unwrap();
    assert!(
        header.starts_with("ply\nformat binary_little_endian 1.0\n"),
        "{header}"
    );
    let (mut vertices, mut faces, mut vertex_floats) = (None, None, 0);
    let mut element = "";
    for line in header.lines() {
        let words: Vec<&str> = line.split_whitespace().collect();
        match words[..] {
            ["element", name, count] => {
                element = name;
                let count = Some(count.parse::<usize>().unwrap());
                match name {
                    "vertex" => vertices = count,
                    "face" => faces = count,
                    _ => panic!("{}: unexpected element {name}", path.display()),
                }
            }
            ["property", "float", _] if element == "vertex" => vertex_floats += 1,
            ["property", "list", "uchar", "int", _] if element == "face" => {}
            ["property", ..] => panic!("{}: unexpected {line}", path.display()),
            _ => {}
        }
    }
    let (vertices, faces) = (vertices.unwrap(), faces.unwrap());
    assert!(vertex_floats == 3 || vertex_floats == 6, "{header}");
    let face_start = header_len + vertices * vertex_floats * 4;
    assert_eq!(
        bytes.len(),
        face_start + faces * 13,
        "{}: size does not match the header",
        path.display()
    );
    for face in bytes[face_start..].chunks_exact(13) {
        assert_eq!(face[0], 3, "{}: not a triangle", path.display());
        for index in face[1..].chunks_exact(4) {
            let index = i32::from_le_bytes(index.try_into().unwrap());
            assert!(
                (0..vertices as i32).contains(&index),
                "{}: index {index} of {vertices}",
                path.display()
            );
        }
    }
    (vertices, faces)
}

/// Vertex and triangle counts of an OBJ mesh as tobj reads it.
fn obj_mesh(path: &Path) -> (usize, usize) {
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ..Default::default()
    };
    let (models, _) =
        tobj::load_obj(path, &options).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let (mut vertices, mut triangles) = (0, 0);
    for model in models {
        let mesh = model.mesh;
        let count = mesh.positions.len() / 3;
        assert!(
            mesh.indices.iter().all(|&i| (i as usize) < count),
            "{}: index out of range",
            path.display()
        );
        vertices += count;
        triangles += mesh.indices.len() / 3;
    }
    (vertices, triangles)
}

/// A mesh of the test ball: a few thousand triangles.
fn assert_ball_mesh(triangles: usize, what: &Path) {
    assert!(
        (1_000..100_000).contains(&triangles),
        "{}: {triangles} triangles",
        what.display()
    );
}

#[test]
fn every_input_format_gives_the_same_mesh() {
    let dir = TempDir::new("formats");
    let points = ball();
    assert!((1_000..3_000).contains(&points.len()), "{}", points.len());
    let inputs = [
        (dir.file("in/binary.ply", ply_binary(&points)), None),
        (dir.file("in/ascii.ply", ply_ascii(&points)), None),
        (dir.file("in/header.csv", csv(&points, true)), None),
        (dir.file("in/plain.csv", csv(&points, false)), None),
        (dir.file("in/raw.bin", raw(&points)), None),
        (dir.file("in/raw.dat", raw(&points)), Some("raw")),
    ];
    let mut reference: Option<(PathBuf, Vec<u8>)> = None;
    for (k, (input, input_format)) in inputs.iter().enumerate() {
        let output = dir.path(&format!("out/{k}.ply"));
        let override_format = match input_format {
            Some(f) => vec!["--input-format", f],
            None => vec![],
        };
        splash![
            "recon",
            input,
            SPACING,
            "--format",
            "ply",
            "-o",
            output,
            override_format
        ]
        .assert_success();
        let bytes = fs::read(&output).unwrap();
        match &reference {
            None => {
                let (_, triangles) = ply_mesh(&output);
                assert_ball_mesh(triangles, input);
                reference = Some((input.clone(), bytes));
            }
            Some((first, expected)) => assert!(
                bytes == *expected,
                "the mesh from {} differs from the one from {}",
                input.display(),
                first.display()
            ),
        }
    }
}

#[test]
fn thread_count_does_not_change_the_mesh() {
    let dir = TempDir::new("threads");
    let input = fixture("frame_0040.ply");
    let mut meshes = Vec::new();
    for threads in ["1", "2"] {
        let output = dir.path(&format!("threads-{threads}.ply"));
        splash![
            "recon",
            input,
            "--spacing",
            "0.014",
            "--cell",
            "r",
            "--threads",
            threads,
            "-o",
            output
        ]
        .assert_success();
        let (_, triangles) = ply_mesh(&output);
        assert!(triangles > 10_000, "{triangles} triangles");
        meshes.push(fs::read(&output).unwrap());
    }
    assert!(
        meshes[0] == meshes[1],
        "1 and 2 threads give different meshes"
    );
}

#[test]
fn bad_inputs_are_reported_and_write_nothing() {
    let dir = TempDir::new("bad-inputs");
    let points = ball();
    let xyz = "property float x\nproperty float y\nproperty float z\n";
    let mut truncated = ply_binary(&points[..100]);
    truncated.truncate(truncated.len() - 12 * 90 + 5);
    let mut nan = points.clone();
    nan[2].y = f32::NAN;
    let text_row = csv_with_row(&points, "0.1,abc,0.2");
    let short_row = csv_with_row(&points, "0.1,0.2");
    let nan_row = csv_with_row(&points, "NaN,0.2,0.3");
    let no_z = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n\
                end_header\n0 0\n1 1\n";
    // File name, contents (none: the file is missing), what stderr must say.
    type Case<'a> = (&'a str, Option<Vec<u8>>, &'a [&'a str]);
    let cases: Vec<Case> = vec![
        ("missing.ply", None, &["cannot open the file"]),
        (
            "points.pts",
            Some(csv(&points, false).into()),
            &["cannot tell the particle format", "extension"],
        ),
        (
            "huge.ply",
            Some(
                format!(
                    "ply\nformat binary_little_endian 1.0\nelement vertex 10000000000000\n\
                     {xyz}end_header\n"
                )
                .into(),
            ),
            &["10000000000000", "truncated"],
        ),
        (
            "truncated.ply",
            Some(truncated),
            &["truncated", "100 vertex records", "after 10 complete"],
        ),
        ("no_z.ply", Some(no_z.into()), &["no property 'z'"]),
        (
            "text.csv",
            Some(text_row.into()),
            &["line 3", "'abc' is not a number"],
        ),
        (
            "short.csv",
            Some(short_row.into()),
            &["line 3", "only 2 columns"],
        ),
        (
            "nan.csv",
            Some(nan_row.into()),
            &["line 3", "non-finite coordinate"],
        ),
        (
            "nan.ply",
            Some(ply_binary(&nan)),
            &["vertex 2", "non-finite coordinate"],
        ),
    ];
    for (name, contents, expected) in cases {
        let input = match contents {
            Some(bytes) => dir.file(&format!("in/{name}"), bytes),
            None => dir.path(&format!("in/{name}")),
        };
        let out = dir.path(&format!("out-{name}"));
        let run = splash![
            "recon",
            input,
            "--spacing",
            "0.01",
            "--cell",
            "r",
            "-o",
            dir.out_dir(&format!("out-{name}"))
        ];
        run.assert_failure()
            .assert_stderr_has(&input.display().to_string())
            .assert_stderr_has("1 of 1 frames failed");
        for want in expected {
            run.assert_stderr_has(want);
        }
        assert_eq!(entries(&out), Vec::<String>::new(), "{}", run.command);
    }
}

#[test]
fn bad_options_are_refused_before_any_work() {
    let dir = TempDir::new("bad-options");
    let input = dir.file("frame.ply", ply_binary(&ball()));
    let out = dir.path("out");
    let cases: &[(&[&str], &[&str])] = &[
        (&["--cell", "foo"], &["--cell", "'foo'", "not a length"]),
        (&["--format", "stl"], &["unknown mesh format 'stl'"]),
        (&["--input-format", "stl"], &["unknown input format 'stl'"]),
        (&["--threads", "0"], &["--threads must be at least 1"]),
        (&["--spacing", "0"], &["spacing must be a positive length"]),
        // Cells far larger than the spacing: 1e30 spun for ever, 0.5 wrote an empty mesh.
        (
            &["--cell", "1e30"],
            &["cell 1.00e30 (1.00e32r", "at most 4r"],
        ),
        (
            &["--cell", "0.5"],
            &["cell 0.5 (50r for r = 0.01)", "at most 4r"],
        ),
        (
            &["--cell", "5r"],
            &["cell 5r is far larger than the particle spacing"],
        ),
        (
            &["--spacing", "1", "--cell", "1000"],
            &["cell 1000 (1000r for r = 1)"],
        ),
        // Given with --spacing 0.01.
        (
            &["--particle-radius", "0.005"],
            &["--particle-radius", "cannot be used with"],
        ),
    ];
    for (args, expected) in cases {
        let spacing = if args.contains(&"--spacing") {
            vec![]
        } else {
            vec!["--spacing", "0.01"]
        };
        let run = splash![
            "recon",
            input,
            "-o",
            dir.out_dir("out"),
            spacing,
            args.to_vec()
        ];
        run.assert_failure();
        for want in *expected {
            run.assert_stderr_has(want);
        }
        assert!(!run.stderr.contains("[1/1]"), "{}", run.stderr);
        assert_eq!(entries(&out), Vec::<String>::new(), "{}", run.command);
    }
}

#[test]
fn an_output_name_must_name_the_mesh_format() {
    let dir = TempDir::new("output-extension");
    let input = dir.file("frame.ply", ply_binary(&ball()));
    // OBJ text in a .stl exited 0.
    splash![
        "recon",
        &input,
        "-o",
        dir.path("mesh.stl"),
        "--spacing",
        "0.01"
    ]
    .assert_failure()
    .assert_stderr_has(".stl extension is not a mesh format");
    splash![
        "recon",
        &input,
        "-o",
        dir.path("mesh.ply"),
        "--format",
        "obj",
        "--spacing",
        "0.01"
    ]
    .assert_failure()
    .assert_stderr_has("--format obj does not match the output name's .ply extension");
    assert_eq!(entries(&dir.path("")), ["frame.ply"]);
    // Asked for explicitly, or without an extension to contradict, the format stands.
    splash![
        "recon",
        &input,
        "-o",
        dir.path("mesh.dat"),
        "--format",
        "ply",
        "--spacing",
        "0.01"
    ]
    .assert_success();
    splash!["recon", &input, "-o", dir.path("mesh"), "--spacing", "0.01"].assert_success();
    assert!(
        fs::read_to_string(dir.path("mesh"))
            .unwrap()
            .starts_with("# ")
    );
    assert!(
        fs::read(dir.path("mesh.dat"))
            .unwrap()
            .starts_with(b"ply\n")
    );
}

#[test]
fn one_bad_frame_does_not_stop_the_others() {
    let dir = TempDir::new("one-bad");
    let points = ball();
    let good1 = dir.file("in/frame_0001.ply", ply_binary(&points));
    let bad = dir.file("in/frame_0002.csv", "x,y,z\n0,0,0\n1,abc,2\n");
    let good2 = dir.file("in/frame_0003.bin", raw(&points));
    let out = dir.path("out");
    let run = splash![
        "recon",
        good1,
        bad,
        good2,
        "--spacing",
        "0.01",
        "--cell",
        "r",
        "-o",
        dir.out_dir("out")
    ];
    run.assert_failure()
        .assert_stderr_has("[3/3]")
        .assert_stderr_has("1 of 3 frames failed")
        .assert_stderr_has(&format!("\n  {}: ", bad.display()))
        .assert_stderr_has("'abc' is not a number");
    assert_eq!(entries(&out), ["frame_0001.obj", "frame_0003.obj"]);
    let first = obj_mesh(&out.join("frame_0001.obj"));
    assert_ball_mesh(first.1, &good1);
    assert_eq!(obj_mesh(&out.join("frame_0003.obj")), first);
}

#[test]
fn an_empty_frame_writes_an_empty_mesh() {
    let dir = TempDir::new("empty");
    let input = dir.file("in/empty.ply", ply_binary(&[]));
    for format in ["obj", "ply"] {
        let out = dir.path(format);
        splash![
            "recon",
            input,
            "--spacing",
            "0.01",
            "--format",
            format,
            "-o",
            dir.out_dir(format)
        ]
        .assert_success()
        .assert_stderr_has("no particles")
        .assert_stderr_has("empty mesh");
        let mesh = out.join(format!("empty.{format}"));
        let counts = match format {
            "obj" => obj_mesh(&mesh),
            _ => ply_mesh(&mesh),
        };
        assert_eq!(counts, (0, 0), "{}", mesh.display());
    }
}

#[test]
fn an_empty_first_frame_needs_no_spacing() {
    let dir = TempDir::new("empty-first");
    let empty = dir.file("in/frame_0001.ply", ply_binary(&[]));
    let good = dir.file("in/frame_0002.ply", ply_binary(&ball()));
    splash!["recon", empty, good, "-o", dir.out_dir("out")].assert_success();
    assert_eq!(obj_mesh(&dir.path("out/frame_0001.obj")), (0, 0));
}

#[test]
fn output_directory_and_default_names_follow_the_stem() {
    let dir = TempDir::new("names");
    let input = dir.file("in/drop_0007.bin", raw(&ball()));
    splash!["recon", input, SPACING].assert_success();
    assert_eq!(
        entries(&dir.path("in")),
        ["drop_0007.bin", "drop_0007_surface.obj"]
    );
    splash!["recon", input, SPACING, "-o", dir.out_dir("out")].assert_success();
    assert_eq!(entries(&dir.path("out")), ["drop_0007.obj"]);
    let beside = fs::read(dir.path("in/drop_0007_surface.obj")).unwrap();
    assert!(beside == fs::read(dir.path("out/drop_0007.obj")).unwrap());
}

#[test]
fn output_patterns_number_frames() {
    let dir = TempDir::new("patterns");
    let points = ball();
    let a = dir.file("in/frame_0040.ply", ply_binary(&points));
    let b = dir.file("in/frame_7.ply", ply_binary(&points));
    let pattern = format!("{}/fluid_{{frame:04}}.obj", dir.path("out").display());
    splash![
        "recon",
        a,
        b,
        "--spacing",
        "0.01",
        "--cell",
        "r",
        "-o",
        pattern
    ]
    .assert_success();
    assert_eq!(
        entries(&dir.path("out")),
        ["fluid_0007.obj", "fluid_0040.obj"]
    );
    let pattern = format!("{}/{{stem}}-mesh.ply", dir.path("stem").display());
    splash![
        "recon",
        a,
        "--spacing",
        "0.01",
        "--cell",
        "r",
        "-o",
        pattern
    ]
    .assert_success();
    assert_eq!(entries(&dir.path("stem")), ["frame_0040-mesh.ply"]);
    ply_mesh(&dir.path("stem/frame_0040-mesh.ply"));
}

#[test]
fn one_file_name_for_two_inputs_is_refused_before_any_work() {
    let dir = TempDir::new("one-name");
    let points = ball();
    let a = dir.file("in/a.ply", ply_binary(&points));
    let b = dir.file("in/b.ply", ply_binary(&points));
    let run = splash![
        "recon",
        a,
        b,
        "--spacing",
        "0.01",
        "-o",
        dir.path("out/mesh.obj")
    ];
    run.assert_failure()
        .assert_stderr_has("names one file for 2 inputs");
    assert!(!run.stderr.contains("[1/2]"), "{}", run.stderr);
    assert_eq!(entries(&dir.path("out")), Vec::<String>::new());
}

#[test]
fn two_inputs_with_one_output_are_refused_before_any_work() {
    let dir = TempDir::new("same-stem");
    let points = ball();
    let a = dir.file("a/frame.ply", ply_binary(&points));
    let b = dir.file("b/frame.csv", csv(&points, true));
    let run = splash!["recon", a, b, "--spacing", "0.01", "-o", dir.out_dir("out")];
    run.assert_failure()
        .assert_stderr_has("would both be written to")
        .assert_stderr_has(&a.display().to_string())
        .assert_stderr_has(&b.display().to_string());
    assert!(!run.stderr.contains("[1/2]"), "{}", run.stderr);
    assert_eq!(entries(&dir.path("out")), Vec::<String>::new());
}

#[test]
fn an_output_over_its_own_input_is_refused() {
    let dir = TempDir::new("over-input");
    let contents = ply_binary(&ball());
    let input = dir.file("frames/frame.ply", &contents);
    let run = splash![
        "recon",
        input,
        "--spacing",
        "0.01",
        "--format",
        "ply",
        "-o",
        dir.out_dir("frames")
    ];
    assert!(
        fs::read(&input).unwrap() == contents,
        "the input was overwritten"
    );
    run.assert_failure();
}

#[test]
fn an_existing_output_is_replaced_whole_or_left_alone() {
    let dir = TempDir::new("replace");
    let points = ball();
    let good = dir.file("good/frame.ply", ply_binary(&points));
    let bad = dir.file("bad/frame.ply", {
        let mut bytes = ply_binary(&points);
        bytes.truncate(bytes.len() / 2);
        bytes
    });
    let fresh = dir.path("fresh/frame.ply");
    splash!["recon", good, SPACING, ["--format", "ply"], "-o", fresh].assert_success();
    let expected = fs::read(&fresh).unwrap();
    // Longer than the mesh: a write in place would leave its tail behind.
    let sentinel = b"not a mesh\n".repeat(expected.len() / 5);
    let target = dir.file("out/frame.ply", &sentinel);
    let out = dir.out_dir("out");

    splash!["recon", bad, SPACING, ["--format", "ply"], "-o", out]
        .assert_failure()
        .assert_stderr_has("truncated");
    assert!(
        fs::read(&target).unwrap() == sentinel,
        "a failed frame changed the existing output"
    );
    assert_eq!(entries(&dir.path("out")), ["frame.ply"]);

    splash!["recon", good, SPACING, ["--format", "ply"], "-o", out].assert_success();
    assert!(
        fs::read(&target).unwrap() == expected,
        "the existing output was not replaced by the mesh"
    );
    assert_eq!(entries(&dir.path("out")), ["frame.ply"]);
}

#[test]
fn particle_radius_is_half_the_spacing() {
    let dir = TempDir::new("radius");
    let input = dir.file("frame.ply", ply_binary(&ball()));
    let by_spacing = dir.path("spacing.ply");
    let by_radius = dir.path("radius.ply");
    splash![
        "recon",
        input,
        "--spacing",
        "0.01",
        "--cell",
        "r",
        "-o",
        by_spacing
    ]
    .assert_success();
    splash![
        "recon",
        input,
        "--particle-radius",
        "0.005",
        "--cell",
        "r",
        "-o",
        by_radius
    ]
    .assert_success();
    let (_, triangles) = ply_mesh(&by_spacing);
    assert_ball_mesh(triangles, &by_spacing);
    assert!(fs::read(&by_spacing).unwrap() == fs::read(&by_radius).unwrap());
}

#[test]
fn spacing_is_estimated_when_not_given() {
    let dir = TempDir::new("estimate");
    let input = dir.file("frame.ply", ply_binary(&ball()));
    let output = dir.path("frame.obj");
    splash!["recon", input, "--cell", "r", "-o", output]
        .assert_success()
        .assert_stderr_has("estimated particle spacing");
    let (_, triangles) = obj_mesh(&output);
    assert!(triangles > 0, "{}: empty mesh", output.display());
    // The cell's limit applies once the spacing is known: here, per frame.
    fs::remove_file(&output).unwrap();
    splash!["recon", input, "--cell", "0.06", "-o", output]
        .assert_failure()
        .assert_stderr_has("cell 0.06 (5.9")
        .assert_stderr_has("at most 4r");
    assert!(!output.exists());
}

#[test]
fn completion_scripts_name_every_subcommand() {
    let script = |shell: &str| {
        let output = Command::new(env!("CARGO_BIN_EXE_splash"))
            .args(["completions", shell])
            .output()
            .expect("cannot start splash");
        assert!(output.status.success(), "splash completions {shell} failed");
        String::from_utf8(output.stdout).unwrap()
    };
    let (bash, zsh, fish) = (script("bash"), script("zsh"), script("fish"));
    assert!(
        bash.contains("complete -F _splash"),
        "bash: no completion function"
    );
    assert!(zsh.starts_with("#compdef splash"), "zsh: no #compdef line");
    for sub in ["recon", "iso", "preview", "config", "bench", "completions"] {
        assert!(bash.contains(&format!("splash,{sub})")), "bash: no {sub}");
        assert!(zsh.contains(&format!("'{sub}:")), "zsh: no {sub}");
        assert!(fish.contains(&format!("-a \"{sub}\"")), "fish: no {sub}");
    }
    splash!["completions", "tcsh"]
        .assert_failure()
        .assert_stderr_has("invalid value 'tcsh'");
}
