//! Broken VTK, VTK XML, BGEO and XYZ files: each gives a clear error naming the file and what
//! is wrong, quickly (no allocation by a declared count), and no damage panics.

mod common;

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use common::TempDir;
use splash_sph::read_particles;

fn fixture(name: &str) -> Vec<u8> {
    fs::read(common::repository().join("fixtures/formats").join(name)).unwrap()
}

fn text(name: &str) -> String {
    String::from_utf8(fixture(name)).unwrap()
}

fn assert_fails(path: &Path, expected: &[&str]) {
    common::assert_read_fails(path, None, expected);
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

fn replace_once(text: &str, from: &str, to: &str) -> String {
    assert!(text.contains(from), "no '{from}'");
    text.replacen(from, to, 1)
}

#[test]
fn bad_legacy_vtk_files_are_reported() {
    let dir = TempDir::new("bad-vtk");
    let ascii = text("legacy_polydata_ascii_v42.vtk");
    let binary = fixture("legacy_binary.vtk");
    let points_at = binary.windows(6).position(|w| w == b"POINTS").unwrap();
    let cases: Vec<(&str, Vec<u8>, &[&str])> = vec![
        (
            "not.vtk",
            b"ply\nformat ascii 1.0\n".to_vec(),
            &["not a legacy VTK file"],
        ),
        (
            "encoding.vtk",
            replace_once(&ascii, "ASCII", "EBCDIC").into(),
            &["ASCII or BINARY", "EBCDIC"],
        ),
        (
            "image.vtk",
            replace_once(&ascii, "POLYDATA", "STRUCTURED_POINTS").into(),
            &["not a point set"],
        ),
        (
            "huge-ascii.vtk",
            replace_once(&ascii, "POINTS 1916", "POINTS 1000000000000").into(),
            &["more than the rest of the file"],
        ),
        (
            "huge-binary.vtk",
            {
                let mut b = binary[..points_at].to_vec();
                b.extend_from_slice(b"POINTS 1000000000000 float\n\0\0\0\0");
                b
            },
            &["truncated binary data", "1000000000000"],
        ),
        (
            "truncated.vtk",
            binary[..points_at + 400].to_vec(),
            &["truncated binary data"],
        ),
        (
            "word.vtk",
            replace_once(&ascii, "0.0301031", "zero").into(),
            &["'zero'", "not a number"],
        ),
        (
            "nan.vtk",
            replace_once(&ascii, "0.0301031", "nan").into(),
            &["non-finite"],
        ),
        (
            "count.vtk",
            replace_once(&ascii, "POINT_DATA 1916", "POINT_DATA 1915").into(),
            &["POINT_DATA", "1916 points"],
        ),
        (
            "keyword.vtk",
            replace_once(&ascii, "POINT_DATA 1916", "PIXEL_DATA 1916").into(),
            &["unknown or unsupported keyword 'PIXEL_DATA'"],
        ),
        (
            "type.vtk",
            replace_once(&ascii, "POINTS 1916 float", "POINTS 1916 quaternion").into(),
            &["unsupported data type 'quaternion'"],
        ),
        (
            "nopoints.vtk",
            b"# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\n".to_vec(),
            &["no POINTS"],
        ),
        (
            "short-field.vtk",
            replace_once(&ascii, "density 1 1916 float", "density 1 44 float").into(),
            &["44 tuples"],
        ),
    ];
    for (name, bytes, expected) in cases {
        assert_fails(&dir.file(name, bytes), expected);
    }
}

#[test]
fn bad_vtk_xml_files_are_reported() {
    let dir = TempDir::new("bad-vtu");
    let binary = text("xml_binary.vtu");
    let zlib = text("xml_binary_zlib.vtu");
    let ascii = text("xml_ascii.vtu");
    let appended = fixture("xml_appended_raw_zlib_uint64.vtu");
    let data_at = appended
        .windows(14)
        .position(|w| w == b"<AppendedData ")
        .unwrap();
    let underscore = data_at + appended[data_at..].iter().position(|&b| b == b'_').unwrap() + 1;
    // Where the positions' compressed data starts (the reader reads them first).
    let points_offset: usize = {
        let after = &appended[appended
            .windows(13)
            .position(|w| w == b"Name=\"Points\"")
            .unwrap()..];
        let digits = &after[after.windows(8).position(|w| w == b"offset=\"").unwrap() + 8..];
        let end = digits.iter().position(|&b| b == b'"').unwrap();
        std::str::from_utf8(&digits[..end])
            .unwrap()
            .parse()
            .unwrap()
    };
    let mut corrupt_zlib = appended.clone();
    // Past the first array's header (3 + 23 blocks of 1 kB: 26 numbers of 8 bytes), into its
    // first zlib block.
    corrupt_zlib[underscore + 240..underscore + 280].fill(0xa5);
    let garbage_at = binary.find("format=\"binary\"").unwrap();
    let garbage_at = garbage_at + binary[garbage_at..].find('>').unwrap() + 1;
    let mut bad_base64 = binary.clone();
    bad_base64.insert_str(garbage_at, "*!^%");
    let cases: Vec<(&str, Vec<u8>, &[&str])> = vec![
        (
            "not.vtu",
            b"<html><body>no</body></html>".to_vec(),
            &["no VTKFile"],
        ),
        (
            "broken.vtu",
            ascii[..ascii.len() / 2].replace("</", "<<").into(),
            &["malformed XML"],
        ),
        (
            "image.vtu",
            replace_once(&ascii, "type=\"UnstructuredGrid\"", "type=\"ImageData\"").into(),
            &["ImageData"],
        ),
        (
            "base64.vtu",
            bad_base64.into(),
            &["invalid base64", "velocity"],
        ),
        ("zlib.vtu", corrupt_zlib, &["zlib block 0", "velocity"]),
        (
            "truncated.vtu",
            appended[..underscore + points_offset + 9000].to_vec(),
            &["truncated compressed data"],
        ),
        (
            "huge-zlib.vtu",
            replace_once(
                &zlib,
                "NumberOfPoints=\"1916\"",
                "NumberOfPoints=\"1000000000000\"",
            )
            .into(),
            &["compression header declares"],
        ),
        (
            "huge-binary.vtu",
            replace_once(
                &binary,
                "NumberOfPoints=\"1916\"",
                "NumberOfPoints=\"1000000000000\"",
            )
            .into(),
            &["header gives"],
        ),
        (
            "huge-ascii.vtu",
            replace_once(
                &ascii,
                "NumberOfPoints=\"1916\"",
                "NumberOfPoints=\"1000000000000\"",
            )
            .into(),
            &["more than its"],
        ),
        (
            "few.vtu",
            replace_once(&ascii, "NumberOfPoints=\"1916\"", "NumberOfPoints=\"1915\"").into(),
            &["more than the 5745 values"],
        ),
        (
            "lz4.vtu",
            replace_once(&zlib, "vtkZLibDataCompressor", "vtkLZ4DataCompressor").into(),
            &["unsupported compressor"],
        ),
        (
            "offset.vtu",
            {
                let t = String::from_utf8_lossy(&appended[..data_at])
                    .replace(&format!("offset=\"{points_offset}\""), "offset=\"9999999\"");
                let mut b = t.into_bytes();
                b.extend_from_slice(&appended[data_at..]);
                b
            },
            &["starts at offset 9999999"],
        ),
        (
            "points.vtu",
            replace_once(&ascii, "<Points>", "<Nothing>")
                .replace("</Points>", "</Nothing>")
                .into(),
            &["no Points array"],
        ),
    ];
    for (name, bytes, expected) in cases {
        assert_fails(&dir.file(name, bytes), expected);
    }
}

#[test]
fn bad_bgeo_files_are_reported() {
    let dir = TempDir::new("bad-bgeo");
    let plain = fixture("partio_attributes.bgeo");
    let with = |at: usize, value: i32| {
        let mut b = plain.clone();
        b[at..at + 4].copy_from_slice(&value.to_be_bytes());
        b
    };
    // A gzip bomb: a header for one point, then 64 MiB of zeros (64 KiB compressed).
    let mut bomb = plain[..41].to_vec();
    bomb[9..13].copy_from_slice(&1i32.to_be_bytes());
    bomb[25..29].copy_from_slice(&0i32.to_be_bytes());
    bomb.resize(41 + (64 << 20), 0);
    let first_type = 41 + 2 + "velocity".len() + 2;
    let cases: Vec<(&str, Vec<u8>, &[&str])> = vec![
        (
            "magic.bgeo",
            b"PGEOV\0\0\0\x05".to_vec(),
            &["not a BGEO file"],
        ),
        ("version.bgeo", with(5, 6), &["unsupported BGEO version 6"]),
        (
            "json.bgeo",
            b"\x7fNSJb[{\"fileversion\"".to_vec(),
            &["JSON BGEO", "not supported yet"],
        ),
        (
            "frame.bgeo.sc",
            b"\x02\x01\x13\x08".to_vec(),
            &["Blosc", "not supported yet"],
        ),
        (
            "truncated.bgeo",
            plain[..plain.len() - 100].to_vec(),
            &["truncated BGEO data", "1913 complete points"],
        ),
        (
            "huge.bgeo",
            with(9, i32::MAX),
            &["truncated BGEO data", "2147483647 points"],
        ),
        ("negative.bgeo", with(9, -5), &["negative"]),
        (
            "type.bgeo",
            with(first_type, 7),
            &["has type 7", "velocity"],
        ),
        (
            "header.bgeo",
            plain[..30].to_vec(),
            &["truncated BGEO data"],
        ),
        (
            "corrupt.bgeo.gz",
            {
                let mut g = gzip(&plain);
                let n = g.len();
                g[n / 2..n / 2 + 64].fill(0x5a);
                g
            },
            &["gzip data is corrupt"],
        ),
        ("bomb.bgeo.gz", gzip(&bomb), &["inflates to more than"]),
    ];
    for (name, bytes, expected) in cases {
        assert_fails(&dir.file(name, bytes), expected);
    }
}

#[test]
fn bad_xyz_files_are_reported() {
    let dir = TempDir::new("bad-xyz");
    let raw = fixture("raw.xyz");
    let mut nan = raw.clone();
    nan[16..20].copy_from_slice(&f32::NAN.to_le_bytes());
    let cases: Vec<(&str, Vec<u8>, &[&str])> = vec![
        (
            "odd.xyz",
            raw[..raw.len() - 5].to_vec(),
            &["not a multiple of 12"],
        ),
        ("nan.xyz", nan, &["non-finite"]),
        ("word.xyz", b"1 2 3\n4 five 6\n".to_vec(), &["five"]),
        ("short.xyz", b"1 2 3\n4 5\n".to_vec(), &["line 2"]),
    ];
    for (name, bytes, expected) in cases {
        assert_fails(&dir.file(name, bytes), expected);
    }
}

/// Every truncation and many single-byte corruptions of one file per reader path: errors or
/// particles, never a panic.
#[test]
fn damaged_interchange_files_never_panic() {
    let dir = TempDir::new("damaged-interchange");
    for name in [
        "legacy_binary.vtk",
        "legacy_polydata_ascii_v42.vtk",
        "splishsplash.vtk",
        "xml_binary_zlib.vtu",
        "xml_appended_raw_zlib_uint64.vtu",
        "xml_appended_base64.vtu",
        "partio_attributes.bgeo",
        "partio_attributes.bgeo.gz",
        "raw.xyz",
    ] {
        let bytes = fixture(name);
        // Densely through the headers (the first kB), then 40 places spread over the data:
        // every read costs the whole file, so a fixed count keeps the test's time bounded.
        let places = |step: usize| {
            let head = bytes.len().min(1024);
            (0..head)
                .step_by(step)
                .chain((head..bytes.len()).step_by((bytes.len() - head) / 40 + 1))
        };
        let mut variants: Vec<Vec<u8>> = places(13).map(|len| bytes[..len].to_vec()).collect();
        for (i, junk) in places(11).zip([0xff, 0x00, b'\n', b'-', b'<', b'9'].iter().cycle()) {
            let mut corrupt = bytes.clone();
            corrupt[i] = *junk;
            variants.push(corrupt);
        }
        let path: PathBuf = dir.path(name);
        for variant in &variants {
            fs::write(&path, variant).unwrap();
            let _ = read_particles(&path, None);
        }
    }
}
