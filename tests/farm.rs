//! Render-farm use of the `splash` binary: frame order, ranges, shards, resumed runs, failures
//! and logs; and the outputs for consumers (POV-Ray, Blender's axes, velocities), read back.

mod common;

use std::collections::BTreeMap;
use std::ffi::OsString;
use std::fs;
use std::path::PathBuf;
use std::process::Command;
use std::time::{Duration, Instant};

use common::{Run, TempDir, entries, finish, fixture, lattice_ball};
use glam::Vec3;
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{DefaultElement, Property};
use splash_sph::io::{MeshFormat, VertexAttributes, write_mesh_with};
use splash_sph::{Config, Length, Reconstructor};

const R: f32 = 0.01;
const FAST: [&str; 4] = ["--spacing", "0.01", "--cell", "r"];

/// A small lattice ball: a few hundred particles, milliseconds per frame.
fn small_ball() -> Vec<Vec3> {
    lattice_ball(Vec3::new(0.1, 0.2, -0.1), 0.04, R)
}

/// A binary PLY of `points`, with `vx vy vz` when `velocities` are given.
fn ply(points: &[Vec3], velocities: Option<&[Vec3]>) -> Vec<u8> {
    let extra = if velocities.is_some() {
        "property float vx\nproperty float vy\nproperty float vz\n"
    } else {
        ""
    };
    let mut out = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\n{extra}end_header\n",
        points.len()
    )
    .into_bytes();
    for (i, p) in points.iter().enumerate() {
        let mut values = p.to_array().to_vec();
        if let Some(v) = velocities {
            values.extend(v[i].to_array());
        }
        for x in values {
            out.extend(x.to_le_bytes());
        }
    }
    out
}

fn splash_env(args: &[OsString], env: &[(&str, &str)]) -> Run {
    let mut command = Command::new(env!("CARGO_BIN_EXE_splash"));
    command
        .arg("recon")
        .args(args)
        .env_remove("SLURM_ARRAY_TASK_ID")
        .env_remove("SLURM_ARRAY_TASK_MIN")
        .env_remove("SLURM_ARRAY_TASK_MAX")
        .env_remove("SLURM_ARRAY_TASK_STEP");
    for (k, v) in env {
        command.env(k, v);
    }
    let output = command.output().expect("cannot start splash");
    let shown: Vec<_> = args.iter().map(|a| a.to_string_lossy()).collect();
    finish(format!("splash recon {}", shown.join(" ")), output)
}

fn args(items: &[&dyn AsRef<std::ffi::OsStr>]) -> Vec<OsString> {
    items.iter().map(|a| a.as_ref().to_owned()).collect()
}

/// `args` followed by the quick reconstruction flags.
fn fast(items: &[&dyn AsRef<std::ffi::OsStr>]) -> Vec<OsString> {
    let mut all = args(items);
    all.extend(FAST.iter().map(OsString::from));
    all
}

/// Frames `numbers` of a small ball (moving by frame) as `dir/in/f_{n}.ply`.
fn sequence(dir: &TempDir, numbers: impl IntoIterator<Item = u64>) -> Vec<PathBuf> {
    let ball = small_ball();
    numbers
        .into_iter()
        .map(|n| {
            let shifted: Vec<Vec3> = ball.iter().map(|p| *p + Vec3::X * n as f32 * R).collect();
            dir.file(&format!("in/f_{n}.ply"), ply(&shifted, None))
        })
        .collect()
}

#[test]
fn frames_run_in_number_order_from_directories_and_patterns() {
    let dir = TempDir::new("order");
    sequence(&dir, [9, 10, 100, 2]);
    dir.file("in/notes.md", "not a frame");
    dir.file("in/.f_3.ply.tmp-1-0", "a hidden temporary");
    let input = dir.path("in");
    let out = format!("{}/", dir.path("out").display());
    let run = splash_env(&fast(&[&input, &"-o", &out, &"--log-format", &"json"]), &[]).ok();
    assert_eq!(run.frames(), [2, 9, 10, 100]);
    // Directory outputs pad frame numbers to 4 digits, for Blender's sequence importers.
    assert_eq!(
        entries(&dir.path("out")),
        ["f_0002.obj", "f_0009.obj", "f_0010.obj", "f_0100.obj"]
    );
    let pattern = format!("{}/f_*.ply", input.display());
    let named = format!("{}/fluid_{{frame:04}}.ply", dir.path("pattern").display());
    let run = splash_env(
        &fast(&[&pattern, &"-o", &named, &"--log-format", &"json"]),
        &[],
    )
    .ok();
    assert_eq!(run.frames(), [2, 9, 10, 100]);
    assert_eq!(
        entries(&dir.path("pattern")),
        [
            "fluid_0002.ply",
            "fluid_0009.ply",
            "fluid_0010.ply",
            "fluid_0100.ply"
        ]
    );
    let nothing = format!("{}/g_*.ply", input.display());
    splash_env(&fast(&[&nothing]), &[])
        .failed()
        .has("matches no file");
    // f_9 and f_0009 would both be f_0009.obj: refused before any work.
    dir.file("in/f_0009.ply", ply(&small_ball(), None));
    let run = splash_env(&fast(&[&input, &"-o", &dir.path("clash/")]), &[])
        .failed()
        .has("would both be written to");
    assert!(!run.stderr.contains("[1/"), "{}", run.stderr);
    assert!(!dir.path("clash").exists());
}

/// A farm re-queue: the same frames written to the same `-o` by two jobs at once. Neither may
/// remove the other's temporary before its rename.
#[test]
fn two_jobs_writing_the_same_frames_both_succeed() {
    let dir = TempDir::new("concurrent");
    sequence(&dir, 1..=8);
    let input = dir.path("in");
    let plain = format!("{}/", dir.path("plain").display());
    splash_env(&fast(&[&input, &"-o", &plain]), &[]).ok();
    for round in 0..5 {
        let out = format!("{}/", dir.path(&format!("out{round}")).display());
        let start = || {
            Command::new(env!("CARGO_BIN_EXE_splash"))
                .arg("recon")
                .args(fast(&[&input, &"-o", &out]))
                .output()
        };
        let (a, b) = std::thread::scope(|s| {
            let a = s.spawn(start);
            let b = s.spawn(start);
            (a.join().unwrap(), b.join().unwrap())
        });
        for output in [a, b] {
            let output = output.expect("cannot start splash");
            finish(format!("round {round}"), output).ok();
        }
        let out = dir.path(&format!("out{round}"));
        assert_eq!(entries(&out), entries(&dir.path("plain")), "round {round}");
        for name in entries(&out) {
            assert_eq!(
                fs::read(out.join(&name)).unwrap(),
                fs::read(dir.path("plain").join(&name)).unwrap(),
                "round {round}: {name}"
            );
        }
    }
}

/// A scanned directory's frames are its numbered files of the commonest extension; stray
/// notes were read as CSV frames (and failed the job) or written out as meshes.
#[test]
fn files_beside_the_frame_sequence_are_skipped_with_a_warning() {
    let dir = TempDir::new("strays");
    sequence(&dir, 1..=3);
    dir.file("in/notes.txt", "remember to check the viscosity");
    dir.file("in/readme.txt", "");
    dir.file("in/f_2.csv", "x,y,z\n0,0,0\n");
    let input = dir.path("in");
    let out = format!("{}/", dir.path("out").display());
    let run = splash_env(&fast(&[&input, &"-o", &out]), &[]).ok();
    assert_eq!(
        entries(&dir.path("out")),
        ["f_0001.obj", "f_0002.obj", "f_0003.obj"]
    );
    let warning = run
        .stderr
        .lines()
        .find(|l| l.starts_with("warning: 3 files"))
        .unwrap_or_else(|| panic!("{}", run.stderr));
    for name in ["f_2.csv", "notes.txt", "readme.txt"] {
        assert!(warning.contains(name), "{warning}");
    }
    // Without any frame number, the commonest extension still decides.
    let flat = TempDir::new("strays-flat");
    flat.file("in/ball.ply", ply(&small_ball(), None));
    flat.file("in/notes.txt", "not a frame");
    let run = splash_env(&fast(&[&flat.path("in"), &"-o", &flat.path("out/")]), &[]).ok();
    assert_eq!(entries(&flat.path("out")), ["ball.obj"]);
    assert!(run.stderr.contains("notes.txt"), "{}", run.stderr);
}

#[test]
fn ranges_and_shards_cover_every_frame_exactly_once() {
    let dir = TempDir::new("shards");
    sequence(&dir, 1..=12);
    let input = dir.path("in");
    let run = splash_env(
        &fast(&[
            &input,
            &"--frames",
            &"2-8x3,11",
            &"-o",
            &dir.path("range/"),
            &"--log-format",
            &"json",
        ]),
        &[],
    )
    .ok();
    assert_eq!(run.frames(), [2, 5, 8, 11]);
    for n in [1, 2, 3, 5, 12, 13] {
        let mut seen: BTreeMap<u64, usize> = BTreeMap::new();
        for k in 1..=n {
            let shard = format!("{k}/{n}");
            let run = splash_env(
                &fast(&[
                    &input,
                    &"--shard",
                    &shard,
                    &"-o",
                    &dir.path(&format!("n{n}/")),
                    &"--log-format",
                    &"json",
                ]),
                &[],
            )
            .ok();
            for f in run.frames() {
                *seen.entry(f).or_default() += 1;
            }
        }
        let expected: BTreeMap<u64, usize> = (1..=12).map(|f| (f, 1)).collect();
        assert_eq!(seen, expected, "{n} shards");
        assert_eq!(entries(&dir.path(&format!("n{n}"))).len(), 12);
    }
    // auto/N: K = SLURM_ARRAY_TASK_ID mod N + 1. Task 3 of the array 1-4 is shard 4/4, and
    // resubmitted alone (sbatch --array=3: the array's bounds become 3) it does the same frames.
    let auto = |bounds: (&str, &str), step: &str| {
        splash_env(
            &fast(&[
                &input,
                &"--shard",
                &"auto/4",
                &"-o",
                &dir.path("auto/"),
                &"--log-format",
                &"json",
            ]),
            &[
                ("SLURM_ARRAY_TASK_ID", "3"),
                ("SLURM_ARRAY_TASK_MIN", bounds.0),
                ("SLURM_ARRAY_TASK_MAX", bounds.1),
                ("SLURM_ARRAY_TASK_STEP", step),
            ],
        )
    };
    for bounds in [("1", "4"), ("3", "3")] {
        let run = auto(bounds, "1").ok();
        assert_eq!(run.frames(), [4, 8, 12], "array {bounds:?}");
        assert_eq!(run.events("start")[0].get("shard"), "\"4/4\"");
    }
    auto(("1", "7"), "2").failed().has("a step of 2");
    splash_env(&fast(&[&input, &"--shard", &"auto/4"]), &[])
        .failed()
        .has("SLURM_ARRAY_TASK_ID is not set");
}

/// A frame the reconstruction takes a while on: the real fixture, cell r/2.
fn slow_sequence(dir: &TempDir, frames: u64) -> Vec<PathBuf> {
    let bytes = fs::read(fixture("frame_0040.ply")).unwrap();
    (1..=frames)
        .map(|n| dir.file(&format!("in/frame_{n:04}.ply"), &bytes))
        .collect()
}

#[test]
fn a_killed_run_restarted_with_skip_existing_finishes_the_sequence() {
    let dir = TempDir::new("resume");
    slow_sequence(&dir, 5);
    let input = dir.path("in");
    let out = dir.path("out");
    let common = ["--spacing", "0.014", "--cell", "r/2", "--skip-existing"];
    let mut child = Command::new(env!("CARGO_BIN_EXE_splash"))
        .arg("recon")
        .arg(&input)
        .arg("-o")
        .arg(format!("{}/", out.display()))
        .args(common)
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // Kill it once the first mesh is there, most likely in the middle of the second frame.
    let start = Instant::now();
    while !out.join("frame_0001.obj").exists() && start.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let done_before = entries(&out).iter().filter(|n| !n.starts_with('.')).count();
    if done_before == 5 {
        eprintln!("notice: the run finished before it was killed; only the restart is tested");
    }
    // What a kill during a write leaves: a hidden temporary, never the final name.
    fs::write(out.join(".frame_0003.obj.tmp-999999-0"), b"v 1 2").unwrap();
    let first = fs::read(out.join("frame_0001.obj")).unwrap();

    let run = splash_env(
        &args(&[
            &input,
            &"-o",
            &format!("{}/", out.display()),
            &common[0],
            &common[1],
            &common[2],
            &common[3],
            &common[4],
            &"--log-format",
            &"json",
        ]),
        &[],
    )
    .ok();
    let start = &run.events("start")[0];
    assert_eq!(
        start.get("skipped"),
        done_before.to_string(),
        "{}",
        run.stderr
    );
    assert_eq!(run.frames().len(), 5 - done_before);
    assert!(!run.frames().contains(&1));
    assert_eq!(
        entries(&out),
        (1..=5)
            .map(|n| format!("frame_{n:04}.obj"))
            .collect::<Vec<_>>(),
        "the temporaries are gone, every frame is there"
    );
    assert!(fs::read(out.join("frame_0001.obj")).unwrap() == first);
    // Every frame is the same input, so a complete sequence has five equal meshes.
    for n in 2..=5 {
        let mesh = fs::read(out.join(format!("frame_{n:04}.obj"))).unwrap();
        assert!(mesh == first, "frame {n} differs from frame 1");
    }
}

#[test]
fn a_bad_frame_is_summarised_and_fail_fast_stops() {
    let dir = TempDir::new("bad");
    sequence(&dir, [1, 2, 4]);
    dir.file(
        "in/f_3.ply",
        "ply\nformat ascii 1.0\nelement vertex 1\nend_header\n1 2 3\n",
    );
    let input = dir.path("in");
    let run = splash_env(&fast(&[&input, &"-o", &dir.path("out/")]), &[])
        .failed()
        .has("1 of 4 frames failed:")
        .has("f_3.ply: cannot read particles");
    assert!(run.stderr.contains("[4/4]"), "{}", run.stderr);
    assert_eq!(
        entries(&dir.path("out")),
        ["f_0001.obj", "f_0002.obj", "f_0004.obj"]
    );
    let run = splash_env(
        &fast(&[&input, &"-o", &dir.path("json/"), &"--log-format", &"json"]),
        &[],
    )
    .failed();
    let summary = &run.events("summary")[0];
    assert_eq!(summary.get("ok"), "false");
    assert_eq!(summary.get("written"), "3");
    let failed = summary.get("failed");
    assert!(
        failed.starts_with("[{\"frame\":3,") && failed.contains("no property 'x'"),
        "{failed}"
    );
    splash_env(
        &fast(&[&input, &"-o", &dir.path("ff/"), &"--fail-fast"]),
        &[],
    )
    .failed()
    .has("1 of 4 frames failed")
    .has("1 frames not attempted");
    assert_eq!(entries(&dir.path("ff")), ["f_0001.obj", "f_0002.obj"]);
    // Quiet: only the failure.
    let run = splash_env(&fast(&[&input, &"-o", &dir.path("q/"), &"-q"]), &[]).failed();
    assert_eq!(run.stderr.lines().count(), 3, "{}", run.stderr);
}

#[test]
fn plain_log_lines_have_time_and_counts() {
    let dir = TempDir::new("plain");
    sequence(&dir, [5]);
    let run = splash_env(&fast(&[&dir.path("in"), &"-o", &dir.path("out/")]), &[]).ok();
    let line = run.stderr.lines().find(|l| l.contains("[1/1]")).unwrap();
    // 2025-01-31T12:00:00Z [1/1] …/f_5.ply -> …/f_0005.obj: 257 particles, 1234 triangles, 0.01 s
    let (time, rest) = line.split_once(' ').unwrap();
    assert!(
        time.len() == 20 && time.ends_with('Z') && time.as_bytes()[10] == b'T',
        "{line}"
    );
    assert!(
        rest.contains(" particles, ") && rest.contains(" triangles, ") && rest.ends_with(" s"),
        "{line}"
    );
}

/// Vertices, normals, extra vertex properties and faces of a PLY file.
type PlyMesh = (Vec<Vec3>, Vec<Vec3>, Vec<Vec3>, Vec<[u32; 3]>);

fn read_ply(bytes: &[u8], extra: [&str; 3]) -> PlyMesh {
    let ply = Parser::<DefaultElement>::new()
        .read_ply(&mut &bytes[..])
        .unwrap();
    let f = |p: &Property| match p {
        Property::Float(v) => *v,
        other => panic!("not a float: {other:?}"),
    };
    let triple = |e: &DefaultElement, names: [&str; 3]| {
        Vec3::from_array(names.map(|n| e.get(n).map_or(f32::NAN, f)))
    };
    let vertex = &ply.payload["vertex"];
    let faces = ply.payload["face"]
        .iter()
        .map(|e| match &e["vertex_indices"] {
            Property::ListInt(l) => [l[0], l[1], l[2]].map(|i| i as u32),
            other => panic!("{other:?}"),
        })
        .collect();
    (
        vertex.iter().map(|e| triple(e, ["x", "y", "z"])).collect(),
        vertex
            .iter()
            .map(|e| triple(e, ["nx", "ny", "nz"]))
            .collect(),
        vertex.iter().map(|e| triple(e, extra)).collect(),
        faces,
    )
}

#[test]
fn meshes_read_back_equal_with_velocities_and_axes() {
    let dir = TempDir::new("readback");
    let particles = small_ball();
    let velocity = Vec3::new(0.5, -1.0, 2.0);
    let velocities = vec![velocity; particles.len()];
    let input = dir.file("in/f_1.ply", ply(&particles, Some(&velocities)));
    let config = Config {
        spacing: Some(R),
        cell: Length::Spacings(1.0),
        ..Config::default()
    };
    let mesh = Reconstructor::new(config)
        .unwrap()
        .reconstruct(&particles)
        .unwrap()
        .mesh;
    assert!(mesh.triangles.len() > 100);

    // OBJ through tobj: the same floats (shortest round-trip text) and faces.
    splash_env(&fast(&[&input, &"-o", &dir.path("obj/")]), &[]).ok();
    let options = tobj::LoadOptions {
        single_index: true,
        ..Default::default()
    };
    let (models, _) = tobj::load_obj(dir.path("obj/f_0001.obj"), &options).unwrap();
    let read = &models[0].mesh;
    let corners: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
    assert_eq!(read.indices.len(), corners.len());
    for (&i, &j) in corners.iter().zip(&read.indices) {
        let (i, j) = (i as usize, j as usize);
        assert_eq!(Vec3::from_slice(&read.positions[3 * j..]), mesh.vertices[i]);
        assert_eq!(Vec3::from_slice(&read.normals[3 * j..]), mesh.normals[i]);
    }

    // PLY with velocities: positions, normals and faces as in memory; every vertex moves with
    // the particles' uniform velocity.
    let run = splash_env(
        &fast(&[
            &input,
            &"-o",
            &dir.path("ply/"),
            &"--format",
            &"ply",
            &"--attributes",
            &"velocity",
        ]),
        &[],
    )
    .ok();
    let bytes = fs::read(dir.path("ply/f_0001.ply")).unwrap();
    let (v, n, u, faces) = read_ply(&bytes, ["vx", "vy", "vz"]);
    assert_eq!(
        (v, n, faces),
        (
            mesh.vertices.clone(),
            mesh.normals.clone(),
            mesh.triangles.clone()
        )
    );
    assert!(
        u.iter().all(|u| (*u - velocity).length() < 1e-5),
        "{}",
        run.stderr
    );
    // The library writes the same bytes.
    let mut direct = Vec::new();
    let vertex_velocities = vec![velocity; mesh.vertices.len()];
    let attributes = VertexAttributes {
        velocities: Some(&vertex_velocities),
        ..Default::default()
    };
    write_mesh_with(&mesh, &attributes, MeshFormat::PlyBinary, &mut direct).unwrap();
    assert_eq!(
        read_ply(&direct, ["vx", "vy", "vz"]).2,
        read_ply(&bytes, ["vx", "vy", "vz"]).2
    );

    // --up-axis z: (x, y, z) → (x, −z, y) for positions, normals and velocities.
    splash_env(
        &fast(&[
            &input,
            &"-o",
            &dir.path("up/"),
            &"--format",
            &"ply",
            &"--attributes",
            &"velocity",
            &"--up-axis",
            &"z",
        ]),
        &[],
    )
    .ok();
    let (v, n, u, faces) = read_ply(
        &fs::read(dir.path("up/f_0001.ply")).unwrap(),
        ["vx", "vy", "vz"],
    );
    let turn = |a: &Vec3| Vec3::new(a.x, -a.z, a.y);
    assert_eq!(v, mesh.vertices.iter().map(turn).collect::<Vec<_>>());
    assert_eq!(n, mesh.normals.iter().map(turn).collect::<Vec<_>>());
    assert!(u.iter().all(|u| (*u - turn(&velocity)).length() < 1e-5));
    assert_eq!(faces, mesh.triangles);

    // Velocities need an input that has them, and a PLY or VTK output.
    let plain = dir.file("plain/f_1.ply", ply(&particles, None));
    splash_env(
        &fast(&[
            &plain,
            &"-o",
            &dir.path("p/"),
            &"--format",
            &"ply",
            &"--attributes",
            &"velocity",
        ]),
        &[],
    )
    .failed()
    .has("has no particle attribute 'velocity'; it has none");
    splash_env(
        &fast(&[&input, &"-o", &dir.path("o/"), &"--attributes", &"velocity"]),
        &[],
    )
    .failed()
    .has("needs PLY, VTK, VTU, VTP, USD or VDB output");
    // The output directory is made (and checked) before the frames; nothing is written in it.
    assert!(!dir.path("o").exists());
    assert_eq!(std::fs::read_dir(dir.path("p")).unwrap().count(), 0);
}

#[test]
fn real_velocities_are_interpolated_onto_the_mesh() {
    let frame = fixture("frame_0010.ply");
    let dir = TempDir::new("real-velocity");
    splash_env(
        &args(&[
            &frame,
            &"-o",
            &dir.path("out/"),
            &"--format",
            &"ply",
            &"--attributes",
            &"velocity",
            &"--spacing",
            &"0.014",
            &"--cell",
            &"r",
        ]),
        &[],
    )
    .ok();
    let (v, _, u, _) = read_ply(
        &fs::read(dir.path("out/frame_0010.ply")).unwrap(),
        ["vx", "vy", "vz"],
    );
    assert_eq!(u.len(), v.len());
    let fastest = u.iter().map(|u| u.length()).fold(0.0, f32::max);
    let mean = u.iter().map(|u| u.length()).sum::<f32>() / u.len() as f32;
    // A breaking dam a few tenths of a second in: metres per second, some surface moving.
    assert!(u.iter().all(|u| u.is_finite()));
    assert!(
        mean > 0.05 && fastest < 20.0,
        "mean {mean}, fastest {fastest}"
    );
}

/// Vertex and face counts declared in a mesh2 include, after checking its blocks' sizes and
/// every index.
fn pov_counts(text: &str) -> (usize, usize) {
    let block = |name: &str| -> (usize, Vec<String>) {
        let start = text.find(name).unwrap_or_else(|| panic!("no {name}"));
        let body = &text[start + name.len()..];
        let body = &body[body.find('{').unwrap() + 1..body.find('}').unwrap()];
        let (count, items) = body.split_once(',').unwrap();
        let items: Vec<String> = items
            .split('>')
            .map(|s| {
                s.trim()
                    .trim_start_matches(',')
                    .trim()
                    .trim_start_matches('<')
                    .to_owned()
            })
            .filter(|s| !s.is_empty())
            .collect();
        (count.trim().parse().unwrap(), items)
    };
    let (vertices, vs) = block("vertex_vectors");
    let (normals, ns) = block("normal_vectors");
    let (faces, fs) = block("face_indices");
    assert_eq!(
        (vs.len(), normals, ns.len(), fs.len()),
        (vertices, vertices, vertices, faces)
    );
    for v in vs.iter().chain(&ns) {
        let xyz: Vec<f32> = v.split(',').map(|x| x.parse().unwrap()).collect();
        assert!(xyz.len() == 3 && xyz.iter().all(|x| x.is_finite()), "<{v}>");
    }
    for f in &fs {
        let abc: Vec<usize> = f.split(',').map(|x| x.parse().unwrap()).collect();
        assert!(abc.len() == 3 && abc.iter().all(|&i| i < vertices), "<{f}>");
    }
    (vertices, faces)
}

#[test]
fn pov_ray_includes_parse_and_render() {
    let dir = TempDir::new("pov");
    let frame = fixture("frame_0040.ply");
    let empty = dir.file("in/frame_0041.ply", ply(&[], None));
    let run = splash_env(
        &args(&[
            &frame,
            &empty,
            &"--format",
            &"pov",
            &"-o",
            &dir.path("pov/"),
            &"--spacing",
            &"0.014",
            &"--cell",
            &"r",
        ]),
        &[],
    )
    .ok();
    let text = fs::read_to_string(dir.path("pov/frame_0040.inc")).unwrap();
    assert!(
        text.contains("#declare SplashMesh = mesh2 {"),
        "{}",
        &text[..200]
    );
    let (vertices, faces) = pov_counts(&text);
    assert!(faces > 10_000 && vertices > 5_000, "{}", run.stderr);
    let empty_text = fs::read_to_string(dir.path("pov/frame_0041.inc")).unwrap();
    assert!(
        empty_text.contains("#declare SplashMesh = union {}"),
        "{empty_text}"
    );

    if Command::new("povray").arg("--version").output().is_err() {
        eprintln!(
            "notice: povray is not installed; skipped the renders, checked the includes only"
        );
        return;
    }
    // The README's scene, rendered small, with its command lines' frame options. The fluid is
    // blue; the ground is grey and the sky pale.
    let scene = include_str!("../examples/scene.pov");
    fs::write(dir.path("scene.pov"), scene).unwrap();
    let povray = |options: &[&str]| {
        let output = Command::new("povray")
            .current_dir(&dir.0)
            .args([
                "+Iscene.pov",
                "+Oframe.ppm",
                "+FP",
                "+W96",
                "+H54",
                "-D",
                "-V",
                // One render thread: with two, the same include now and then came out one
                // pixel apart (660 against 661 fluid pixels).
                "+WT1",
            ])
            .args(options)
            .output()
            .unwrap();
        // POV-Ray wraps its messages at 80 columns.
        let stderr = String::from_utf8_lossy(&output.stderr);
        let stderr = stderr.split_whitespace().collect::<Vec<_>>().join(" ");
        (output.status.success(), stderr)
    };
    let blue = |image: &str| {
        let path = dir.path(image);
        let pixels = blue_pixels(&fs::read(&path).unwrap());
        fs::remove_file(path).unwrap();
        pixels
    };
    // One frame: declared, or as an animation of one frame.
    let copy = |from: u32, to: u32| {
        let inc = |n| dir.path(&format!("pov/frame_{n:04}.inc"));
        fs::copy(inc(from), inc(to)).unwrap();
    };
    copy(40, 1);
    for (options, image, water) in [
        (&["Declare=Frame=40"][..], "frame.ppm", true),
        (&["Declare=Frame=41"], "frame.ppm", false),
        (&["+KFI40", "+KFF40"], "frame40.ppm", true),
        // POV-Ray turns animation off here, and frame_number is 0.
        (&["+KFI1", "+KFF1"], "frame.ppm", true),
    ] {
        let (ok, stderr) = povray(options);
        assert!(ok, "povray {options:?} failed:\n{stderr}");
        let pixels = blue(image);
        assert_eq!(
            pixels > 200,
            water,
            "{pixels} fluid pixels with {options:?}"
        );
    }
    // Every 3rd frame, from 40: files 40, 43 (empty) and 46, and none between them.
    copy(41, 43);
    copy(40, 46);
    fs::remove_file(dir.path("pov/frame_0041.inc")).unwrap();
    let (ok, stderr) = povray(&["+KFI40", "+KFF46", "+STP3"]);
    assert!(ok, "povray +KFI40 +KFF46 +STP3 failed:\n{stderr}");
    let pixels = ["frame40.ppm", "frame43.ppm", "frame46.ppm"].map(blue);
    assert!(
        pixels[0] > 200 && pixels[1] == 0 && pixels[2] == pixels[0],
        "fluid pixels {pixels:?}"
    );
    // A frame number without a file is named.
    let (ok, stderr) = povray(&["+KFI40", "+KFF46", "+STP2"]);
    assert!(
        !ok && stderr.contains("no pov/frame_0042.inc for frame 42"),
        "{stderr}"
    );
}

/// Pixels of a binary PPM (P6, 8 bit) that are clearly blue.
fn blue_pixels(ppm: &[u8]) -> usize {
    let mut fields = Vec::new();
    let mut at = 0;
    while fields.len() < 4 {
        while ppm[at].is_ascii_whitespace() {
            at += 1;
        }
        if ppm[at] == b'#' {
            while ppm[at] != b'\n' {
                at += 1;
            }
            continue;
        }
        let start = at;
        while !ppm[at].is_ascii_whitespace() {
            at += 1;
        }
        fields.push(String::from_utf8_lossy(&ppm[start..at]).into_owned());
    }
    assert_eq!((fields[0].as_str(), fields[3].as_str()), ("P6", "255"));
    let pixels = &ppm[at + 1..];
    pixels
        .chunks_exact(3)
        .filter(|p| u16::from(p[2]) > u16::from(p[0]) + 60)
        .count()
}

#[test]
fn velocities_are_read_beside_the_positions() {
    let dir = TempDir::new("positions");
    let points = small_ball();
    let velocities = vec![Vec3::ONE; points.len()];
    let with = dir.file("v.ply", ply(&points, Some(&velocities)));
    let read = splash_sph::read_particles(&with, None).unwrap();
    assert_eq!(read.positions, points);
    let velocity = splash_sph::Attribute::Vector(velocities);
    assert_eq!(read.attributes["velocity"], velocity);
}

#[test]
fn velocities_come_from_text_tables_too_and_must_be_finite() {
    let dir = TempDir::new("csv-velocity");
    let mut text = "x,y,z,vx,vy,vz\n".to_owned();
    for p in small_ball() {
        text += &format!("{},{},{},0.5,-1,2\n", p.x, p.y, p.z);
    }
    let input = dir.file("in/f_1.csv", &text);
    let velocity = ["--format", "ply", "--attributes", "velocity"];
    let run = |input: &PathBuf| {
        let mut all = fast(&[input, &"-o", &dir.path("out/")]);
        all.extend(velocity.iter().map(OsString::from));
        splash_env(&all, &[])
    };
    run(&input).ok();
    let (_, _, u, _) = read_ply(
        &fs::read(dir.path("out/f_0001.ply")).unwrap(),
        ["vx", "vy", "vz"],
    );
    assert!(!u.is_empty());
    assert!(
        u.iter()
            .all(|u| (*u - Vec3::new(0.5, -1.0, 2.0)).length() < 1e-5)
    );

    let bad = dir.file("in/f_2.csv", text.replacen("0.5,-1,2", "0.5,NaN,2", 1));
    run(&bad)
        .failed()
        .has("cannot read velocities from '")
        .has("f_2.csv': particle 0 has a non-finite velocity (0.5, NaN, 2)");
}
