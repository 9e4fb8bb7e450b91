//! `splash recon --format vdb` end to end on the bundled frame, read back by OpenVDB's own
//! tools (Debian's libopenvdb-tools; the tests say they skipped without them): `vdb_print`
//! finds the level set and the attribute grids, and `vdb_tool` meshes the level set into a
//! surface of the same volume as splash's mesh, lying on it; `splash iso --format vdb` writes an
//! isosurface's level set with its attribute grids. And a bad output path is an error naming
//! the file that leaves nothing behind.

mod common;

use std::path::Path;
use std::process::Command;

use common::{TempDir, finish, fixture};
use splash_sph::io::read_mesh;
use splash_sph::mesh::{SignedDistance, TriMesh};

/// The fixture's spacing, and cells of r: fast.
const FAST: [&str; 4] = ["--spacing", "0.014", "--cell", "r"];
const CELL: f32 = 0.014;

fn recon(output: &Path, args: &[&str]) -> common::Run {
    let frame = fixture("frame_0040.ply");
    let out = Command::new(env!("CARGO_BIN_EXE_splash"))
        .arg("recon")
        .arg(&frame)
        .args(FAST)
        .args(args)
        .arg("-o")
        .arg(output)
        .output()
        .expect("cannot start splash");
    finish(
        format!("splash recon {} {}", frame.display(), args.join(" ")),
        out,
    )
}

/// The output of an OpenVDB tool, or None (with a note) when it is not installed.
fn tool(name: &str, args: &[&str]) -> Option<String> {
    match Command::new(name).args(args).output() {
        Ok(out) => {
            assert!(
                out.status.success(),
                "{name} {args:?}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
            Some(String::from_utf8_lossy(&out.stdout).into_owned())
        }
        Err(_) => {
            println!("skipped: {name} not installed (apt-get install libopenvdb-tools)");
            None
        }
    }
}

/// An OBJ of triangles and quads (vdb_tool's), triangulated.
fn quads_obj(path: &Path) -> TriMesh {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let (models, _) = tobj::load_obj(path, &options).unwrap();
    let mut mesh = TriMesh::default();
    for m in models {
        let base = mesh.vertices.len() as u32;
        let p = &m.mesh.positions;
        mesh.vertices
            .extend(p.chunks(3).map(|c| splash_sph::Vec3::new(c[0], c[1], c[2])));
        mesh.triangles.extend(
            m.mesh
                .indices
                .chunks(3)
                .map(|t| [base + t[0], base + t[1], base + t[2]]),
        );
    }
    mesh
}

fn volume(mesh: &TriMesh) -> f64 {
    mesh.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.vertices[i as usize].as_dvec3());
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

/// The distances from the vertices of `from` to the surface of `to` (infinite beyond
/// `reach`), sorted.
fn distances(from: &TriMesh, to: &TriMesh, reach: f32) -> Vec<f32> {
    let sd = SignedDistance::new(&to.vertices, &to.triangles, reach);
    let mut d: Vec<f32> = from
        .vertices
        .iter()
        .map(|&v| sd.at(v).map_or(f32::INFINITY, f32::abs))
        .collect();
    d.sort_by(f32::total_cmp);
    d
}

/// Whether `vdb_print` is installed; when it is, checks that it lists in `file` the level set
/// `surface`, the velocity grid `v` and the density grid, on the same nonzero count of active
/// voxels and voxels of the fixture's cell.
fn lists_three_grids_on_one_band(file: &Path) -> bool {
    let Some(listing) = tool("vdb_print", &["-l", file.to_str().unwrap()]) else {
        return false;
    };
    for expected in [
        "Name: surface",
        "class: level set",
        "Name: v",
        "Tree_vec3s_5_4_3",
        "Name: density",
        "voxel size: 0.014",
    ] {
        assert!(listing.contains(expected), "no {expected} in\n{listing}");
    }
    let counts: Vec<&str> = listing
        .lines()
        .filter(|l| l.contains("file_voxel_count"))
        .collect();
    assert!(
        counts.len() == 3 && counts.iter().all(|c| *c == counts[0]) && !counts[0].ends_with(" 0"),
        "{counts:?}"
    );
    true
}

#[test]
fn openvdb_reads_the_level_set_and_meshes_it_back_onto_the_mesh() {
    let dir = TempDir::new("vdb-read-back");
    let (grids, vdb, ply) = (dir.path("grids.vdb"), dir.path("f.vdb"), dir.path("f.ply"));
    recon(&grids, &["--attributes", "velocity,density"]).ok();
    recon(&vdb, &[]).ok();
    recon(&ply, &[]).ok();
    if !lists_three_grids_on_one_band(&grids) {
        return;
    }
    let back = dir.path("back.obj");
    let args = [
        "-read",
        vdb.to_str().unwrap(),
        "-ls2mesh",
        "-write",
        back.to_str().unwrap(),
    ];
    if tool("vdb_tool", &args).is_none() {
        return;
    }
    let ours = read_mesh(&ply).unwrap().mesh;
    let theirs = quads_obj(&back);
    // OpenVDB's meshes wind the other way: compare volumes' sizes.
    let (v, w) = (volume(&theirs).abs(), volume(&ours));
    assert!(
        (v / w - 1.0).abs() < 0.02,
        "volume {v} from OpenVDB against {w}"
    );
    // Every part of OpenVDB's surface lies on splash's: 99 % of its vertices within half a
    // cell. Not the converse: droplets and sheets thinner than a voxel fall between the voxel
    // centres, where no zero crossing samples them (at cell r on this splashing frame, a tenth
    // of splash's vertices); half of splash's vertices lie within a tenth of a cell.
    let reach = 10.0 * CELL;
    let (there, back_here) = (
        distances(&ours, &theirs, reach),
        distances(&theirs, &ours, reach),
    );
    let quantile = |d: &[f32], q: usize| d[d.len() * q / 100] / CELL;
    assert!(
        quantile(&back_here, 99) < 0.5,
        "{}",
        quantile(&back_here, 99)
    );
    assert!(quantile(&there, 50) < 0.1, "{}", quantile(&there, 50));
    println!(
        "volume ratio {}; OpenVDB's vertices: 99 % within {} cells; splash's: half within {}",
        v / w,
        quantile(&back_here, 99),
        quantile(&there, 50)
    );
}

#[test]
fn isosurfaces_write_level_sets_with_attribute_grids() {
    let dir = TempDir::new("vdb-iso");
    let (frame, out) = (fixture("frame_0040.ply"), dir.path("iso.vdb"));
    let run = Command::new(env!("CARGO_BIN_EXE_splash"))
        .args([
            "iso",
            frame.to_str().unwrap(),
            "--attribute",
            "density",
            "--level",
            "600",
        ])
        .args(FAST)
        .args(["--format", "vdb", "--attributes", "velocity,density", "-o"])
        .arg(&out)
        .output()
        .expect("cannot start splash");
    finish(
        "splash iso --format vdb --attributes velocity,density".into(),
        run,
    )
    .ok();
    lists_three_grids_on_one_band(&out);
}

#[test]
fn a_bad_output_path_names_the_file_and_leaves_nothing() {
    let dir = TempDir::new("vdb-bad-path");
    let blocker = dir.path("file");
    std::fs::write(&blocker, "not a directory").unwrap();
    let target = blocker.join("f.vdb");
    recon(&target, &[])
        .failed()
        .has(&blocker.display().to_string());
    let left: Vec<_> = std::fs::read_dir(&dir.0)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left.len(), 1, "{left:?}");
}
