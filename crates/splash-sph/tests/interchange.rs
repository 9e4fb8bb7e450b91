//! The VTK, VTU/VTP, BGEO and XYZ readers against files written by independent tools
//! (fixtures/formats, made by scripts/make-format-fixtures.py with VTK's Python package,
//! splashsurf and numpy): every file holds every 23rd particle of fixtures/frame_0010.ply (1 916),
//! and must read back to the same positions, bit for bit, and the same attributes.

use std::path::{Path, PathBuf};

use glam::Vec3;
use splash_sph::io::{Attribute, Particles};
use splash_sph::read_particles;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn fixture(name: &str) -> PathBuf {
    root().join("fixtures/formats").join(name)
}

/// Every 23rd particle of the PLY frame, with `id` = its index there.
fn reference() -> Particles {
    let full = read_particles(&root().join("fixtures/frame_0010.ply"), None).unwrap();
    let keep: Vec<usize> = (0..full.len()).step_by(23).collect();
    let mut out = Particles {
        positions: keep.iter().map(|&i| full.positions[i]).collect(),
        ..Particles::default()
    };
    for (name, attribute) in &full.attributes {
        let picked = match attribute {
            Attribute::Scalar(v) => Attribute::Scalar(keep.iter().map(|&i| v[i]).collect()),
            Attribute::Vector(v) => Attribute::Vector(keep.iter().map(|&i| v[i]).collect()),
        };
        out.attributes.insert(name.clone(), picked);
    }
    out.attributes.insert(
        "id".into(),
        Attribute::Scalar(keep.iter().map(|&i| i as f32).collect()),
    );
    out
}

/// The first value that differs (bit for bit when `tolerance` is 0, else relatively).
fn first_difference(got: &[f32], expected: &[f32], tolerance: f32) -> Option<String> {
    if got.len() != expected.len() {
        return Some(format!("{} values, expected {}", got.len(), expected.len()));
    }
    got.iter()
        .zip(expected)
        .enumerate()
        .find_map(|(i, (&g, &e))| {
            let same = if tolerance == 0.0 {
                g.to_bits() == e.to_bits()
            } else {
                (g - e).abs() <= tolerance * e.abs().max(1e-3)
            };
            (!same).then(|| {
                format!(
                    "value {i}: {g} (bits {:#x}), expected {e} (bits {:#x})",
                    g.to_bits(),
                    e.to_bits()
                )
            })
        })
}

fn flat(points: &[Vec3]) -> Vec<f32> {
    points.iter().flat_map(|p| p.to_array()).collect()
}

fn values(attribute: &Attribute) -> Vec<f32> {
    match attribute {
        Attribute::Scalar(v) => v.clone(),
        Attribute::Vector(v) => flat(v),
    }
}

/// Same positions and the same attributes (velocity, density, id) as the PLY: bit for bit, or
/// to `tolerance` (relative) for text files written with fewer digits than f32 needs.
fn check(name: &str, tolerance: f32) {
    let expected = reference();
    let got = read_particles(&fixture(name), None).unwrap_or_else(|e| panic!("{name}: {e}"));
    if let Some(d) = first_difference(&flat(&got.positions), &flat(&expected.positions), tolerance)
    {
        panic!("{name}: positions: {d}");
    }
    let names: Vec<&String> = got.attributes.keys().collect();
    assert_eq!(
        names,
        ["density", "id", "velocity"],
        "{name}: attribute names"
    );
    for (attribute, want) in &expected.attributes {
        let have = &got.attributes[attribute];
        assert_eq!(
            std::mem::discriminant(have),
            std::mem::discriminant(want),
            "{name}: {attribute} is a scalar in one, a vector in the other"
        );
        if let Some(d) = first_difference(&values(have), &values(want), tolerance) {
            panic!("{name}: {attribute}: {d}");
        }
    }
}

fn check_all(name: &str) {
    check(name, 0.0)
}

#[test]
fn legacy_vtk_every_encoding_matches_the_ply() {
    // VTK's ascii writer prints 6 significant digits.
    check("legacy_ascii.vtk", 1e-5);
    check("legacy_polydata_ascii_v42.vtk", 1e-5);
    for name in [
        "legacy_binary.vtk",
        "legacy_binary_v42_double.vtk",
        "legacy_polydata_binary.vtk",
        "splishsplash.vtk",
    ] {
        check_all(name);
    }
}

/// Same positions, bit for bit; no attributes.
fn check_positions(name: &str) -> Particles {
    let expected = reference();
    let got = read_particles(&fixture(name), None).unwrap_or_else(|e| panic!("{name}: {e}"));
    if let Some(d) = first_difference(&flat(&got.positions), &flat(&expected.positions), 0.0) {
        panic!("{name}: positions: {d}");
    }
    got
}

#[test]
fn xyz_raw_and_text_match_the_ply() {
    // numpy's tofile (splashsurf's .xyz) and savetxt with 9 digits (round-trips f32).
    for name in ["raw.xyz", "text.xyz"] {
        let got = check_positions(name);
        assert!(got.attributes.is_empty(), "{name}");
    }
}

#[test]
fn bgeo_from_splashsurf_matches_the_ply() {
    // `splashsurf convert` writes gzip-compressed BGEO even under a plain .bgeo name.
    check_positions("splashsurf.bgeo");
}

#[test]
fn vtk_xml_every_encoding_matches_the_ply() {
    check("xml_ascii.vtu", 1e-5);
    for name in [
        "xml_binary.vtu",
        "xml_binary_zlib.vtu",
        "xml_binary_zlib_uint64.vtu",
        "xml_appended_raw.vtu",
        "xml_appended_raw_zlib_uint64.vtu",
        "xml_appended_base64.vtu",
        "xml_appended_base64_zlib.vtu",
        "xml_binary_zlib_uint64_double.vtp",
        "xml_appended_raw.vtp",
    ] {
        check_all(name);
    }
}

#[test]
fn bgeo_with_attributes_matches_the_ply() {
    // Laid out as partio writes it, gzipped and plain; the script checks the .gz with the
    // BGEO reader pysplashsurf adds to meshio.
    check_all("partio_attributes.bgeo.gz");
    check_all("partio_attributes.bgeo");
}
