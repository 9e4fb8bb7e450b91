//! `splash recon` on the interchange formats: the same mesh, byte for byte, from the PLY of a
//! particle set and from its VTK, VTU, BGEO and XYZ versions written by independent tools
//! (fixtures/formats), and `.bgeo.gz` sequences in directories and patterns.

mod common;

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

use common::{TempDir, entries, repository};

fn formats(name: &str) -> PathBuf {
    repository().join("fixtures/formats").join(name)
}

fn splash(args: &[&std::ffi::OsStr]) -> (bool, String) {
    let output = Command::new(env!("CARGO_BIN_EXE_splash"))
        .args(args)
        .output()
        .expect("cannot start splash");
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(
        output.status.code().is_some() && !stderr.contains("panicked"),
        "{stderr}"
    );
    (output.status.success(), stderr)
}

fn recon(input: &Path, extra: &[&str], output: &Path) -> String {
    let mut args: Vec<&std::ffi::OsStr> = vec!["recon".as_ref(), input.as_os_str()];
    args.extend(
        ["--spacing", "0.05", "--cell", "r", "--format", "ply", "-o"].map(std::ffi::OsStr::new),
    );
    args.push(output.as_os_str());
    args.extend(extra.iter().map(std::ffi::OsStr::new));
    let (ok, stderr) = splash(&args);
    assert!(ok, "{}: {stderr}", input.display());
    stderr
}

#[test]
fn every_interchange_format_gives_the_ply_mesh() {
    let dir = TempDir::new("interchange-mesh");
    // The PLY of the fixtures' particles (every 23rd of frame_0010), from the raw .xyz.
    let raw = fs::read(formats("raw.xyz")).unwrap();
    let mut ply = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty float x\n\
         property float y\nproperty float z\nend_header\n",
        raw.len() / 12
    )
    .into_bytes();
    ply.extend(&raw);
    let ply = dir.file("in/particles.ply", ply);
    let reference = dir.path("out/reference.ply");
    recon(&ply, &[], &reference);
    let expected = fs::read(&reference).unwrap();
    assert!(
        expected.len() > 10_000,
        "a mesh of {} bytes",
        expected.len()
    );
    let inputs = [
        "legacy_binary.vtk",
        "legacy_binary_v42_double.vtk",
        "splishsplash.vtk",
        "xml_binary.vtu",
        "xml_appended_raw_zlib_uint64.vtu",
        "xml_appended_base64_zlib.vtu",
        "xml_binary_zlib_uint64_double.vtp",
        "partio_attributes.bgeo",
        "partio_attributes.bgeo.gz",
        "splashsurf.bgeo",
        "raw.xyz",
        "text.xyz",
    ];
    for (k, name) in inputs.iter().enumerate() {
        let output = dir.path(&format!("out/{k}.ply"));
        recon(&formats(name), &[], &output);
        assert!(
            fs::read(&output).unwrap() == expected,
            "the mesh from {name} differs from the PLY's"
        );
    }
    // --input-format overrides the extension.
    let renamed = dir.file(
        "in/particles.dat",
        fs::read(formats("xml_appended_raw.vtu")).unwrap(),
    );
    let output = dir.path("out/renamed.ply");
    recon(&renamed, &["--input-format", "vtu"], &output);
    assert!(fs::read(&output).unwrap() == expected, "--input-format vtu");
}

#[test]
fn bgeo_gz_sequences_are_scanned_and_matched() {
    let dir = TempDir::new("interchange-sequence");
    let bgeo = fs::read(formats("partio_attributes.bgeo.gz")).unwrap();
    for name in [
        "sim/fluid_9.bgeo.gz",
        "sim/fluid_10.bgeo.gz",
        "sim/fluid_10.bgeo",
    ] {
        dir.file(name, &bgeo);
    }
    dir.file("sim/notes.txt", "not a frame\n");
    // A directory: the .bgeo.gz frames (the commonest extension), named by their stem.
    let out = dir.path("dir/");
    let (ok, stderr) = splash(&[
        "recon".as_ref(),
        dir.path("sim").as_os_str(),
        "--spacing".as_ref(),
        "0.05".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert!(ok, "{stderr}");
    assert!(
        stderr.contains("fluid_10.bgeo") && stderr.contains("notes.txt"),
        "{stderr}"
    );
    assert_eq!(entries(&out), ["fluid_0009.obj", "fluid_0010.obj"]);
    // A pattern, with the frame number before the double extension.
    let pattern = dir.path("sim/fluid_*.bgeo.gz");
    let mesh = dir.path("mesh");
    let (ok, stderr) = splash(&[
        "recon".as_ref(),
        pattern.as_os_str(),
        "--spacing".as_ref(),
        "0.05".as_ref(),
        "-o".as_ref(),
        format!("{}/{{frame:04}}.ply", mesh.display()).as_ref(),
    ]);
    assert!(ok, "{stderr}");
    assert_eq!(entries(&mesh), ["0009.ply", "0010.ply"]);
}
