//! `splash iso` end to end on the bundled real frame: the mesh and its vertex attributes, the
//! errors for an unknown attribute and for a vector without a scalar of it, the JSON log's `iso`
//! figures, and the same bytes whatever the thread count.

mod common;

use std::fs;
use std::path::Path;
use std::process::Command;

use common::{Run, TempDir, finish, fixture};
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{DefaultElement, Ply, Property};

/// The fixture's spacing, and cells of r: a few hundred milliseconds per run.
const FAST: [&str; 4] = ["--spacing", "0.014", "--cell", "r"];

fn iso(args: &[&str]) -> Run {
    let frame = fixture("frame_0040.ply");
    let output = Command::new(env!("CARGO_BIN_EXE_splash"))
        .arg("iso")
        .arg(&frame)
        .args(args)
        .output()
        .expect("cannot start splash");
    finish(
        format!("splash iso {} {}", frame.display(), args.join(" ")),
        output,
    )
}

fn read_ply(path: &Path) -> Ply<DefaultElement> {
    let bytes = fs::read(path).unwrap();
    Parser::<DefaultElement>::new()
        .read_ply(&mut &bytes[..])
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn float(e: &DefaultElement, name: &str) -> f32 {
    match e.get(name) {
        Some(Property::Float(v)) => *v,
        other => panic!("vertex property {name}: {other:?}"),
    }
}

#[test]
fn density_isosurface_has_triangles_and_unit_normals() {
    let dir = TempDir::new("iso-density");
    let out = dir.path("out.ply");
    let out_s = out.to_str().unwrap();
    let args = [
        "--attribute",
        "density",
        "--level",
        "1000",
        "--shepard",
        "-o",
        out_s,
    ];
    iso(&[&args[..], &FAST].concat()).ok();
    let ply = read_ply(&out);
    let vertices = &ply.payload["vertex"];
    let faces = &ply.payload["face"];
    assert!(
        vertices.len() > 1000 && faces.len() > 1000,
        "{} vertices, {} triangles",
        vertices.len(),
        faces.len()
    );
    for v in vertices {
        let n = ["nx", "ny", "nz"].map(|c| float(v, c));
        let length = n.iter().map(|c| c * c).sum::<f32>().sqrt();
        assert!((length - 1.0).abs() < 1e-3, "normal {n:?}");
    }
    for f in faces {
        let Property::ListInt(l) = &f["vertex_indices"] else {
            panic!("{f:?}")
        };
        assert_eq!(l.len(), 3);
        assert!(l.iter().all(|&i| (i as usize) < vertices.len()));
    }
}

/// The fixture's range of densities.
fn density_range() -> (f32, f32) {
    let particles = read_ply(&fixture("frame_0040.ply"));
    particles.payload["vertex"]
        .iter()
        .map(|p| float(p, "density"))
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), d| {
            (lo.min(d), hi.max(d))
        })
}

#[test]
fn speed_isosurface_carries_interpolated_density() {
    let dir = TempDir::new("iso-speed");
    let (lo, hi) = density_range();
    assert!(0.0 < lo && lo < hi, "densities from {lo} to {hi}");
    for shepard in [false, true] {
        let out = dir.path(&format!("v{shepard}.out"));
        let out_s = out.to_str().unwrap();
        let mut args = vec![
            "--attribute",
            "velocity",
            "--magnitude",
            "--level",
            "1.0",
            "--attributes",
            "density",
            "--format",
            "ply",
            "-o",
            out_s,
        ];
        if shepard {
            args.push("--shepard");
        }
        iso(&[&args[..], &FAST].concat()).ok();
        let ply = read_ply(&out);
        let vertices = &ply.payload["vertex"];
        assert!(!vertices.is_empty() && !ply.payload["face"].is_empty());
        for v in vertices {
            let rho = float(v, "density");
            // Plain SPH sums V W ρ_j, whose weights add up to about 1 inside the fluid and
            // less at its surface; Shepard's mean stays within the particles' range.
            let (min, max) = if shepard {
                (lo * (1.0 - 1e-5), hi * (1.0 + 1e-5))
            } else {
                (0.0, 1.5 * hi)
            };
            assert!(
                rho > min && rho <= max,
                "shepard {shepard}: density {rho} outside {min}..{max}"
            );
        }
    }
}

#[test]
fn unknown_attribute_names_the_file_and_lists_the_frame_attributes() {
    let dir = TempDir::new("iso-unknown");
    let out = dir.path("x.ply");
    let args = ["--attribute", "pressure", "--level", "1", "-o"];
    iso(&[&args[..], &[out.to_str().unwrap()], &FAST].concat())
        .failed()
        .has("frame_0040.ply")
        .has("no particle attribute 'pressure'")
        .has("density, velocity");
    assert!(dir.entries().is_empty(), "{:?}", dir.entries());
}

#[test]
fn vector_without_magnitude_fails_clearly() {
    let dir = TempDir::new("iso-vector");
    let out = dir.path("x.ply");
    let args = ["--attribute", "velocity", "--level", "1", "-o"];
    iso(&[&args[..], &[out.to_str().unwrap()], &FAST].concat())
        .failed()
        .has("frame_0040.ply")
        .has("vector attribute")
        .has("--magnitude");
    assert!(dir.entries().is_empty(), "{:?}", dir.entries());
}

#[test]
fn json_log_has_the_iso_figures_and_threads_do_not_change_the_mesh() {
    let dir = TempDir::new("iso-json");
    let mut meshes = Vec::new();
    for threads in ["1", "2"] {
        let out = dir.path(&format!("t{threads}.ply"));
        let args = [
            "--attribute",
            "density",
            "--level",
            "1000",
            "--threads",
            threads,
            "--log-format",
            "json",
            "-o",
            out.to_str().unwrap(),
        ];
        let run = iso(&[&args[..], &FAST].concat()).ok();
        let frames = run.events("frame");
        assert_eq!(frames.len(), 1, "{}", run.stderr);
        let frame = &frames[0];
        assert_eq!(frame.get("status"), "\"ok\"");
        let figures = common::Event(frame.get("iso").to_owned());
        assert_eq!(figures.get("level"), "1000.0");
        for key in ["seed_cells", "visited_cells", "crossed_cells"] {
            let n: u64 = figures.get(key).parse().unwrap();
            assert!(n > 0, "{key} = {n}");
        }
        let ratio: f64 = figures.get("cache_hit_ratio").parse().unwrap();
        assert!((0.0..=1.0).contains(&ratio), "hit ratio {ratio}");
        // The frame's time counts the isosurface's stages (it counted only the read and the
        // write before).
        let stages: serde_json::Value = serde_json::from_str(figures.get("timings")).unwrap();
        let stages: f64 = stages
            .as_object()
            .unwrap()
            .values()
            .map(|d| d["secs"].as_f64().unwrap() + d["nanos"].as_f64().unwrap() * 1e-9)
            .sum();
        let seconds: f64 = frame.get("seconds").parse().unwrap();
        assert!(
            seconds + 1e-3 >= stages && stages > 0.0,
            "{seconds} s, stages {stages} s"
        );
        let triangles: usize = frame.get("triangles").parse().unwrap();
        assert_eq!(figures.get("triangles"), frame.get("triangles"));
        assert_eq!(read_ply(&out).payload["face"].len(), triangles);
        meshes.push(fs::read(&out).unwrap());
    }
    assert!(
        meshes[0] == meshes[1],
        "1 and 2 threads wrote different files"
    );
}

/// `--correct=0` keeps Marching Cubes' vertices (no correction figures), `--correct=1` moves
/// them: the flag reaches iso's Newton steps, not recon's field correction it shares a name with.
#[test]
fn correct_sets_the_newton_steps() {
    let dir = TempDir::new("iso-correct");
    let mut shifts = Vec::new();
    for steps in ["--correct=0", "--correct=1", "--correct"] {
        let out = dir.path("c.ply");
        let args = [
            "--attribute",
            "density",
            "--level",
            "1000",
            steps,
            "--log-format",
            "json",
            "-o",
            out.to_str().unwrap(),
        ];
        let run = iso(&[&args[..], &FAST].concat()).ok();
        let frame = &run.events("frame")[0];
        let figures = common::Event(frame.get("iso").to_owned());
        let correction = common::Event(figures.get("correction").to_owned());
        shifts.push(correction.get("mean").parse::<f64>().unwrap());
    }
    assert_eq!(shifts[0], 0.0, "{shifts:?}");
    assert!(shifts[1] > 0.0 && shifts[2] > 0.0, "{shifts:?}");
}

#[test]
fn recon_only_flags_are_refused_not_ignored() {
    let dir = TempDir::new("iso-recon-flags");
    let out = dir.path("x.ply");
    for flag in [
        "--engine=slices",
        "--field=density",
        "--normals=grid",
        "--block=16",
    ] {
        let args = ["--attribute", "density", "--level", "1000", flag, "-o"];
        iso(&[&args[..], &[out.to_str().unwrap()], &FAST].concat())
            .failed()
            .has(flag.split('=').next().unwrap())
            .has("means nothing to iso");
    }
    assert!(dir.entries().is_empty(), "{:?}", dir.entries());
}

#[test]
fn report_is_refused_with_where_the_figures_are() {
    let dir = TempDir::new("iso-report");
    let out = dir.path("x.ply");
    let report = dir.path("r.md");
    let args = ["--attribute", "density", "--level", "1000", "--report"];
    iso(&[
        &args[..],
        &[report.to_str().unwrap(), "-o", out.to_str().unwrap()],
        &FAST,
    ]
    .concat())
    .failed()
    .has("--report")
    .has("--log-format json");
    assert!(dir.entries().is_empty(), "{:?}", dir.entries());
}

/// An ASCII PLY of a Lamb–Oseen vortex (core 0.2) about the vertical line through (0.5, 0.5),
/// faded along z, on a lattice of spacing 0.05 filling [0, 1]³: its core λ2 < 0 is one closed
/// cigar inside the box.
fn vortex_ply(dir: &TempDir) -> std::path::PathBuf {
    let (r, core) = (0.05f32, 0.2f32);
    let n = 20;
    let mut text = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\n\
         property float z\nproperty float vx\nproperty float vy\nproperty float vz\nend_header\n",
        (n + 1) * (n + 1) * (n + 1)
    );
    for k in 0..=n {
        for j in 0..=n {
            for i in 0..=n {
                let (x, y, z) = (i as f32 * r, j as f32 * r, k as f32 * r);
                let (dx, dy) = (x - 0.5, y - 0.5);
                let rho = (dx * dx + dy * dy).sqrt();
                let speed = if rho > 0.0 {
                    (1.0 - (-(rho / core).powi(2)).exp()) / (2.0 * std::f32::consts::PI * rho)
                        * (-((z - 0.5) / 0.2).powi(2)).exp()
                } else {
                    0.0
                };
                let (vx, vy) = if rho > 0.0 {
                    (-dy / rho * speed, dx / rho * speed)
                } else {
                    (0.0, 0.0)
                };
                text += &format!("{x} {y} {z} {vx} {vy} 0\n");
            }
        }
    }
    dir.file("vortex.ply", text)
}

/// `splash iso INPUT --attribute velocity --lambda2 --level -2 --spacing 0.05 -o OUT`.
fn iso_lambda2(input: &Path, out: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_splash"))
        .arg("iso")
        .arg(input)
        .args(["--attribute", "velocity", "--lambda2", "--level", "-2"])
        .args(["--spacing", "0.05", "-o"])
        .arg(out)
        .output()
        .unwrap()
}

#[test]
fn lambda2_of_a_vortex_is_a_closed_outward_surface_around_its_core() {
    let dir = TempDir::new("iso-lambda2");
    let input = vortex_ply(&dir);
    let out = dir.path("core.ply");
    let output = iso_lambda2(&input, &out);
    finish("splash iso vortex.ply --lambda2".into(), output).ok();
    let ply = read_ply(&out);
    let vertices: Vec<[f32; 3]> = ply.payload["vertex"]
        .iter()
        .map(|v| [float(v, "x"), float(v, "y"), float(v, "z")])
        .collect();
    let faces: Vec<[usize; 3]> = ply.payload["face"]
        .iter()
        .map(|f| {
            let Property::ListInt(l) = &f["vertex_indices"] else {
                panic!("face indices")
            };
            [l[0], l[1], l[2]].map(|i| i as usize)
        })
        .collect();
    assert!(faces.len() > 500, "{} triangles", faces.len());
    // Closed and consistently wound: every directed edge once, its reverse once.
    let mut edges = std::collections::BTreeMap::new();
    for f in &faces {
        for k in 0..3 {
            *edges.entry((f[k], f[(k + 1) % 3])).or_insert(0) += 1;
        }
    }
    for (&(a, b), &count) in &edges {
        assert_eq!((count, edges.get(&(b, a))), (1, Some(&1)), "edge {a}–{b}");
    }
    // Around the axis, inside the radius where λ2 changes sign (1.12 × the core); wound
    // outwards: a positive enclosed volume.
    let volume: f32 = faces
        .iter()
        .map(|f| {
            let [a, b, c] = f.map(|i| glam::Vec3::from(vertices[i]) - glam::Vec3::splat(0.5));
            a.dot(b.cross(c)) / 6.0
        })
        .sum();
    assert!(volume > 0.0, "{volume}");
    for v in &vertices {
        let rho = ((v[0] - 0.5).powi(2) + (v[1] - 0.5).powi(2)).sqrt();
        assert!(rho < 1.12 * 0.2, "{v:?}");
    }
}

#[test]
fn lambda2_without_a_velocity_names_the_file() {
    let dir = TempDir::new("iso-lambda2-missing");
    let input = dir.file(
        "still.ply",
        "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n\
         property float z\nproperty float density\nend_header\n0 0 0 1000\n0.05 0 0 1000\n",
    );
    let out = dir.path("x.ply");
    let output = iso_lambda2(&input, &out);
    finish("splash iso still.ply --lambda2".into(), output)
        .failed()
        .has("still.ply")
        .has("no particle attribute 'velocity'")
        .has("density");
    assert!(!out.exists());
}

/// The paper's kernel scale 0.5 leaves about 2 particles in a support of the fixture (its
/// simulation's support is 2r): a warning; the full scale none.
#[test]
fn a_kernel_scale_leaving_few_neighbours_warns() {
    let dir = TempDir::new("iso-kernel-scale");
    let out = dir.path("x.ply");
    let args = [
        "--attribute",
        "velocity",
        "--magnitude",
        "--level",
        "1.5",
        "-o",
    ];
    let args = [&args[..], &[out.to_str().unwrap()], &FAST].concat();
    let small = iso(&[&args[..], &["--kernel-scale", "0.5"]].concat()).ok();
    small
        .has("warning")
        .has("kernel scale 0.5")
        .has("--kernel-scale");
    let full = iso(&args).ok();
    assert!(!full.stderr.contains("warning"), "{}", full.stderr);
}

/// `splash bench iso`: the paper's five tables, and one JSON record per configuration whose
/// counts are those of `splash iso` (3 quantities × 3 kernel scales × 2 cells × 2 corrections).
#[test]
fn bench_iso_prints_tables_one_to_five_and_writes_every_run() {
    let dir = TempDir::new("bench-iso");
    let json = dir.path("b.json");
    let output = Command::new(env!("CARGO_BIN_EXE_splash"))
        .args(["bench", "iso", fixture("frame_0040.ply").to_str().unwrap()])
        .args(["--spacing", "0.014", "-q", "--json", json.to_str().unwrap()])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    finish("splash bench iso".into(), output).ok();
    for t in [
        "Table I:",
        "Table II:",
        "Table III:",
        "Table IV:",
        "Table V:",
    ] {
        assert!(stdout.contains(t), "{t} missing:\n{stdout}");
    }
    assert!(
        stdout.contains("| Isosurface triangles | 35520 | 7930 | 87310 |"),
        "{stdout}"
    );
    let report: serde_json::Value = serde_json::from_slice(&fs::read(&json).unwrap()).unwrap();
    let runs = report["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 36);
    // The speed at scale 1, cell r/2, corrected: the default `splash iso`'s 87 310 triangles.
    let speed = runs
        .iter()
        .find(|r| r["quantity"] == "speed" && r["cell"] == "r/2" && r["correct"] == 3)
        .unwrap();
    assert_eq!(speed["stats"]["triangles"], 87310);
}
