//! Particle input and mesh output: every format round-trips, bad input is reported precisely.

use std::collections::BTreeMap;
use std::fmt::Write as _;
mod common;

use common::TempDir;
use std::fs;
use std::io::ErrorKind;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use glam::Vec3;
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{
    Addable, DefaultElement, ElementDef, Encoding as PlyEncoding, Ply, Property, PropertyDef,
    PropertyType, ScalarType,
};
use ply_rs_bw::writer::Writer;
use splash_sph::io::{InputFormat, MeshFormat, write_mesh, write_mesh_file};
use splash_sph::mesh::TriMesh;
use splash_sph::{Attribute, Particles};

/// The positions of a particle file.
fn read_particles(path: &Path, format: Option<InputFormat>) -> splash_sph::Result<Vec<Vec3>> {
    splash_sph::read_particles(path, format).map(|p| p.positions)
}

fn particles() -> Vec<Vec3> {
    vec![
        Vec3::new(0.1, -2.5, 3.75),
        Vec3::new(1e-7, 12345.678, -0.0),
        Vec3::new(-1.0e6, 0.333_333_34, 7.0),
        Vec3::new(f32::MIN_POSITIVE, 3.0e38, -123.456),
    ]
}

#[derive(Clone, Copy, Debug)]
enum Encoding {
    Ascii,
    Le,
    Be,
}

/// Appends `value` as PLY type `ty`; `list` stands for `list uchar int` holding [5, 6].
fn encode(ty: &str, value: f64, encoding: Encoding, out: &mut Vec<u8>) {
    macro_rules! put {
        ($t:ty) => {{
            let v = value as $t;
            match encoding {
                Encoding::Ascii => out.extend(format!("{v} ").bytes()),
                Encoding::Le => out.extend(v.to_le_bytes()),
                Encoding::Be => out.extend(v.to_be_bytes()),
            }
        }};
    }
    match ty {
        "float" => put!(f32),
        "double" => put!(f64),
        "uchar" => put!(u8),
        "short" => put!(i16),
        "int" => put!(i32),
        "list" => {
            encode("uchar", 2.0, encoding, out);
            encode("int", 5.0, encoding, out);
            encode("int", 6.0, encoding, out);
        }
        _ => panic!("test encoder has no type {ty}"),
    }
}

/// A PLY file with the given vertex properties (type, name): coordinates from `points`, 7 in the
/// others. `prelude` puts an element with a list property before `vertex`; `trailer` puts a
/// truncated element after it, which must not be read.
fn ply_file(
    encoding: Encoding,
    props: &[(&str, &str)],
    points: &[Vec3],
    prelude: bool,
    trailer: bool,
) -> Vec<u8> {
    let format = match encoding {
        Encoding::Ascii => "ascii",
        Encoding::Le => "binary_little_endian",
        Encoding::Be => "binary_big_endian",
    };
    let mut header = format!("ply\nformat {format} 1.0\ncomment test file\n");
    if prelude {
        header += "element material 2\nproperty uchar id\nproperty list uchar int indices\n";
    }
    writeln!(header, "element vertex {}", points.len()).unwrap();
    for (ty, name) in props {
        let ty = if *ty == "list" { "list uchar int" } else { ty };
        writeln!(header, "property {ty} {name}").unwrap();
    }
    if trailer {
        header += "element face 1\nproperty list uchar int vertex_indices\n";
    }
    header += "end_header\n";
    let mut out = header.into_bytes();
    let end_record = |out: &mut Vec<u8>| {
        if let Encoding::Ascii = encoding {
            out.push(b'\n');
        }
    };
    if prelude {
        for (id, indices) in [(1.0, &[4.0, 5.0, 6.0][..]), (2.0, &[][..])] {
            encode("uchar", id, encoding, &mut out);
            encode("uchar", indices.len() as f64, encoding, &mut out);
            for &i in indices {
                encode("int", i, encoding, &mut out);
            }
            end_record(&mut out);
        }
    }
    for p in points {
        for (ty, name) in props {
            let value = match *name {
                "x" => p.x,
                "y" => p.y,
                "z" => p.z,
                _ => 7.0,
            };
            encode(ty, f64::from(value), encoding, &mut out);
        }
        end_record(&mut out);
    }
    if trailer {
        encode("uchar", 3.0, encoding, &mut out);
    }
    out
}

const FLOAT_XYZ: &[(&str, &str)] = &[("float", "x"), ("float", "y"), ("float", "z")];
const DOUBLE_XYZ: &[(&str, &str)] = &[("double", "x"), ("double", "y"), ("double", "z")];
const ODD_LAYOUT: &[(&str, &str)] = &[
    ("double", "density"),
    ("float", "z"),
    ("uchar", "flag"),
    ("float", "x"),
    ("int", "id"),
    ("double", "y"),
    ("short", "phase"),
];
const WITH_LIST: &[(&str, &str)] = &[
    ("float", "x"),
    ("list", "neighbours"),
    ("float", "y"),
    ("float", "z"),
    ("float", "vx"),
];

fn raw_file(points: &[Vec3]) -> Vec<u8> {
    points
        .iter()
        .flat_map(|p| p.to_array())
        .flat_map(f32::to_le_bytes)
        .collect()
}

fn csv_rows(points: &[Vec3], row: impl Fn(&Vec3) -> String) -> String {
    points.iter().map(row).collect()
}

/// Every test input format, each holding `particles()`.
fn input_files(dir: &TempDir) -> Vec<PathBuf> {
    let points = particles();
    let mut files = vec![
        dir.file(
            "ascii.ply",
            ply_file(Encoding::Ascii, FLOAT_XYZ, &points, false, false),
        ),
        dir.file(
            "le.ply",
            ply_file(Encoding::Le, FLOAT_XYZ, &points, false, false),
        ),
        dir.file(
            "be-double.ply",
            ply_file(Encoding::Be, DOUBLE_XYZ, &points, false, false),
        ),
    ];
    for encoding in [Encoding::Ascii, Encoding::Le, Encoding::Be] {
        let odd = ply_file(encoding, ODD_LAYOUT, &points, true, true);
        files.push(dir.file(&format!("odd-{encoding:?}.ply"), odd));
        let list = ply_file(encoding, WITH_LIST, &points, true, false);
        files.push(dir.file(&format!("list-{encoding:?}.ply"), list));
    }
    let reordered = "id,Z , \"y\",X,extra\r\n".to_owned()
        + &csv_rows(&points, |p| format!("9,{},{},{},abc\r\n", p.z, p.y, p.x));
    files.push(dir.file("header-crlf.csv", reordered));
    let plain = "# exported particles\n\n".to_owned()
        + &csv_rows(&points, |p| format!("{}, {}, {}\n\n", p.x, p.y, p.z));
    files.push(dir.file("plain.csv", plain));
    let semicolons = "\u{feff}x;y;z;rho\n".to_owned()
        + &csv_rows(&points, |p| format!("\"{}\";{};{};1000\n", p.x, p.y, p.z));
    files.push(dir.file("semicolons.csv", semicolons));
    let whitespace = csv_rows(&points, |p| format!("  {}\t{}   {} 0.5\n", p.x, p.y, p.z));
    files.push(dir.file("whitespace.txt", whitespace));
    files.push(dir.file("particles.bin", raw_file(&points)));
    files
}

#[test]
fn every_input_format_reads_the_same_particles() {
    let dir = TempDir::new("formats");
    let files = input_files(&dir);
    assert_eq!(files.len(), 14);
    for path in files {
        let read = read_particles(&path, None).unwrap_or_else(|e| panic!("{e:#}"));
        assert_eq!(read, particles(), "{}", path.display());
    }
    let renamed = dir.file("frame.dat", raw_file(&particles()));
    assert_eq!(
        read_particles(&renamed, Some(InputFormat::Raw)).unwrap(),
        particles()
    );
}

#[test]
fn format_names_and_extensions() {
    assert_eq!(
        InputFormat::from_path(Path::new("a/f.PLY")).unwrap(),
        InputFormat::Ply
    );
    assert_eq!(
        InputFormat::from_path(Path::new("f.txt")).unwrap(),
        InputFormat::Csv
    );
    assert_eq!(
        InputFormat::from_path(Path::new("f.raw")).unwrap(),
        InputFormat::Raw
    );
    assert!(InputFormat::from_path(Path::new("ply")).is_err());
    assert_eq!(InputFormat::parse("CSV").unwrap(), InputFormat::Csv);
    let err = InputFormat::parse("stl").unwrap_err().to_string();
    assert!(
        err.contains("'stl'") && err.contains("ply, csv, raw, vtk, vtu (or vtp), bgeo, xyz"),
        "{err}"
    );
    for (name, format) in [
        ("f.vtk", InputFormat::Vtk),
        ("f.vtu", InputFormat::VtkXml),
        ("f.VTP", InputFormat::VtkXml),
        ("f.bgeo", InputFormat::Bgeo),
        ("fluid.0042.bgeo.gz", InputFormat::Bgeo),
        ("fluid.0042.bgeo.sc", InputFormat::Bgeo),
        ("run.xyz", InputFormat::Xyz),
    ] {
        assert_eq!(
            InputFormat::from_path(Path::new(name)).unwrap(),
            format,
            "{name}"
        );
    }
    assert!(InputFormat::from_path(Path::new("f.tar.gz")).is_err());
    assert_eq!(InputFormat::parse("vtp").unwrap(), InputFormat::VtkXml);
    assert_eq!(InputFormat::parse("BGEO").unwrap(), InputFormat::Bgeo);

    assert_eq!(MeshFormat::parse("ply").unwrap(), MeshFormat::PlyBinary);
    assert_eq!(
        MeshFormat::parse("ply-ascii").unwrap(),
        MeshFormat::PlyAscii
    );
    assert_eq!(MeshFormat::parse("obj").unwrap(), MeshFormat::Obj);
    assert!(MeshFormat::parse("stl").is_err());
    assert_eq!(MeshFormat::PlyAscii.extension(), "ply");
    assert_eq!(MeshFormat::Obj.extension(), "obj");
    assert_eq!(
        MeshFormat::from_path(Path::new("m.OBJ")),
        Some(MeshFormat::Obj)
    );
    assert_eq!(
        MeshFormat::from_path(Path::new("m.ply")),
        Some(MeshFormat::PlyBinary)
    );
    assert_eq!(MeshFormat::from_path(Path::new("m.stl")), None);
}

#[test]
fn empty_frames_are_valid() {
    let dir = TempDir::new("empty");
    let files = [
        dir.file(
            "ascii.ply",
            ply_file(Encoding::Ascii, FLOAT_XYZ, &[], true, true),
        ),
        dir.file(
            "le.ply",
            ply_file(Encoding::Le, ODD_LAYOUT, &[], true, true),
        ),
        dir.file(
            "list.ply",
            ply_file(Encoding::Be, WITH_LIST, &[], false, false),
        ),
        dir.file("header.csv", "x,y,z\n"),
        dir.file("nothing.csv", ""),
        dir.file("nothing.bin", ""),
    ];
    for path in files {
        let read = read_particles(&path, None).unwrap_or_else(|e| panic!("{e:#}"));
        assert!(read.is_empty(), "{}", path.display());
    }
}

fn header(format: &str, vertices: &str, props: &str) -> String {
    format!("ply\nformat {format} 1.0\nelement vertex {vertices}\n{props}end_header\n")
}

const XYZ_PROPS: &str = "property float x\nproperty float y\nproperty float z\n";

/// Reads `path`, which must fail with a message naming the file and holding every `expected`.
fn assert_fails(path: &Path, format: Option<InputFormat>, expected: &[&str]) {
    common::assert_read_fails(path, format, expected);
}

#[test]
fn bad_ply_files_are_reported() {
    let dir = TempDir::new("bad-ply");
    let le = "binary_little_endian";
    let points = raw_file(&particles());
    let with_payload = |text: String, payload: &[u8]| [text.as_bytes(), payload].concat();

    assert_fails(&dir.path("missing.ply"), None, &["cannot open"]);
    let is_dir = dir.path("folder.ply");
    fs::create_dir(&is_dir).unwrap();
    assert_fails(&is_dir, None, &["directory"]);
    assert_fails(
        &dir.file("frame.pts", "1 2 3\n"),
        None,
        &["extension", ".ply, .csv"],
    );
    assert_fails(&dir.file("empty.ply", ""), None, &["not a PLY file"]);
    assert_fails(
        &dir.file("magic.ply", "PLY?\nformat ascii 1.0\n"),
        None,
        &["not a PLY file"],
    );
    let typo = header(
        "ascii",
        "1",
        "property float x\nproperty flaot y\nproperty float z\n",
    );
    assert_fails(
        &dir.file("typo.ply", typo),
        None,
        &["malformed PLY header", "line 5"],
    );
    assert_fails(
        &dir.file("no-end.ply", "ply\nformat ascii 1.0\nelement vertex 1\n"),
        None,
        &["malformed PLY header", "'end_header'"],
    );
    assert_fails(
        &dir.file("no-format.ply", "ply\nelement vertex 0\nend_header\n"),
        None,
        &["malformed PLY header", "format"],
    );
    let twice = header(
        "ascii",
        "0",
        "property float x\nproperty float x\nproperty float y\n",
    );
    assert_fails(&dir.file("twice.ply", twice), None, &["same name"]);
    let no_z = header(
        le,
        "4",
        "property float x\nproperty float y\nproperty float w\n",
    );
    assert_fails(
        &dir.file("no-z.ply", with_payload(no_z, &points)),
        None,
        &["no property 'z'"],
    );
    let list_x = header(
        "ascii",
        "0",
        "property list uchar float x\nproperty float y\nproperty float z\n",
    );
    assert_fails(&dir.file("list-x.ply", list_x), None, &["'x' is a list"]);
    let float_len = header(
        "ascii",
        "0",
        &format!("property list float int n\n{XYZ_PROPS}"),
    );
    assert_fails(
        &dir.file("float-len.ply", float_len),
        None,
        &["non-integer length"],
    );
    let faces = "ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int v\nend_header\n";
    assert_fails(
        &dir.file("faces.ply", faces),
        None,
        &["no 'vertex' element", "face"],
    );

    // Binary payloads: 4 vertices of 12 bytes after a header of `header_len` bytes.
    let truncated = header(le, "4", XYZ_PROPS);
    let header_len = truncated.len();
    let cut = with_payload(truncated, &points[..42]);
    assert_fails(
        &dir.file("cut.ply", cut),
        None,
        &[
            "truncated",
            &format!("byte offset {}", header_len + 42),
            "after 3 complete vertex records",
        ],
    );
    let overcount = with_payload(header(le, "5", XYZ_PROPS), &points);
    assert_fails(
        &dir.file("overcount.ply", overcount),
        None,
        &["expected 5 vertex records"],
    );
    let huge = with_payload(header(le, "10000000000000", XYZ_PROPS), &points);
    assert_fails(
        &dir.file("huge.ply", huge),
        None,
        &["truncated", "10000000000000"],
    );
    let huge_list = header(
        le,
        "10000000000000",
        &format!("property list uchar int n\n{XYZ_PROPS}"),
    );
    let huge_list = with_payload(huge_list, &points);
    assert_fails(
        &dir.file("huge-list.ply", huge_list),
        None,
        &["truncated", "vertex record"],
    );
    let mut nan = points.clone();
    nan[16..20].copy_from_slice(&f32::NAN.to_le_bytes());
    let nan = with_payload(header(le, "4", XYZ_PROPS), &nan);
    assert_fails(
        &dir.file("nan.ply", nan),
        None,
        &["vertex 1 (byte offset", "non-finite"],
    );
    let prelude = ply_file(Encoding::Le, FLOAT_XYZ, &particles(), true, false);
    let payload_start = prelude
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11;
    // Inside the list of the first `material` record.
    let cut_prelude = &prelude[..payload_start + 5];
    assert_fails(
        &dir.file("cut-prelude.ply", cut_prelude),
        None,
        &["truncated", "material record"],
    );
    let negative = header(le, "1", &format!("property list char int n\n{XYZ_PROPS}"));
    let negative = with_payload(negative, &[0xff]);
    assert_fails(
        &dir.file("negative.ply", negative),
        None,
        &["negative list length", "'n'"],
    );

    // Ascii payloads: the first data line is line 8.
    let short = header("ascii", "5", XYZ_PROPS) + "1 2 3\n4 5 6\n\n7 8 9\n";
    assert_fails(
        &dir.file("short.ply", short),
        None,
        &["after 3 of 5 vertices"],
    );
    let huge = header("ascii", "10000000000000", XYZ_PROPS) + "1 2 3\n";
    assert_fails(
        &dir.file("huge-ascii.ply", huge),
        None,
        &["after 1 of 10000000000000"],
    );
    let word = header("ascii", "2", XYZ_PROPS) + "1 2 3\n4 abc 6\n";
    assert_fails(
        &dir.file("word.ply", word),
        None,
        &["line 9 (vertex 1)", "cannot parse 'abc' as property 'y'"],
    );
    let few = header("ascii", "1", XYZ_PROPS) + "1 2\n";
    assert_fails(
        &dir.file("few.ply", few),
        None,
        &["line 8 (vertex 0)", "too few values"],
    );
    let inf = header("ascii", "1", XYZ_PROPS) + "1 inf 3\n";
    assert_fails(
        &dir.file("inf.ply", inf),
        None,
        &["line 8 (vertex 0)", "non-finite"],
    );
}

#[test]
fn bad_text_and_raw_files_are_reported() {
    let dir = TempDir::new("bad-text");
    let word = "x,y,z\n1,2,3\n4,abc,6\n";
    assert_fails(
        &dir.file("word.csv", word),
        None,
        &["line 3, column 2 ('y'): 'abc' is not a number"],
    );
    let short = "1,2,3\n\n4,5\n";
    assert_fails(
        &dir.file("short.csv", short),
        None,
        &["line 3: the row has only 2 columns; missing column 3 ('z')"],
    );
    let no_z = "# comment\nx,y,w\n1,2,3\n";
    assert_fails(
        &dir.file("no-z.csv", no_z),
        None,
        &["line 2", "no column 'z'", "x, y, w"],
    );
    let nan = "x y z\n1 NaN 3\n";
    assert_fails(
        &dir.file("nan.txt", nan),
        None,
        &["line 2 has a non-finite coordinate"],
    );
    assert_fails(
        &dir.file("latin1.csv", b"x,y,z\n1,2,\xe9\n"),
        None,
        &["line 2", "UTF-8"],
    );
    assert_fails(
        &dir.file("odd.bin", [0; 25]),
        None,
        &["25 bytes", "remainder 1"],
    );
    let mut inf = raw_file(&particles());
    inf[32..36].copy_from_slice(&f32::NEG_INFINITY.to_le_bytes());
    assert_fails(
        &dir.file("inf.raw", inf),
        None,
        &["particle 2 (byte offset 24)", "-inf"],
    );
    let text = dir.file("text.ply", "1,2,3\n");
    assert_eq!(
        read_particles(&text, Some(InputFormat::Csv)).unwrap(),
        [Vec3::new(1.0, 2.0, 3.0)]
    );
    assert_fails(&text, Some(InputFormat::Raw), &["6 bytes long"]);
}

/// A failure to read a file is an `Error::Io` with the OS's error kind; bad content is an
/// `Error::Format`.
#[test]
fn errors_say_whose_they_are() {
    let dir = TempDir::new("error-kinds");
    let folder = dir.path("folder.ply");
    fs::create_dir(&folder).unwrap();
    for (path, kind) in [
        (dir.path("missing.ply"), ErrorKind::NotFound),
        (folder, ErrorKind::IsADirectory),
    ] {
        match splash_sph::read_particles(&path, None) {
            Err(splash_sph::Error::Io {
                path: at, io_error, ..
            }) => assert_eq!((at, io_error.kind()), (path, kind)),
            other => panic!("{}: {other:?}", path.display()),
        }
    }
    // The operating system's reason appears once along the chain of causes (the message and
    // its sources, as the CLI prints them), not in the message and again as a source.
    let missing = dir.path("missing.ply");
    let reason = fs::File::open(&missing).unwrap_err().to_string();
    let e = splash_sph::read_particles(&missing, None).unwrap_err();
    let mut chain = e.to_string();
    let mut cause = std::error::Error::source(&e);
    while let Some(c) = cause {
        chain += &format!(": {c}");
        cause = c.source();
    }
    assert_eq!(chain.matches(&reason).count(), 1, "{chain}");
    let bad = dir.file("bad.csv", "x,y,z\n1,2,oops\n");
    match splash_sph::read_particles(&bad, None) {
        Err(splash_sph::Error::Format { path, message }) => {
            assert_eq!(path, bad);
            assert_eq!(message, "line 2, column 3 ('z'): 'oops' is not a number");
        }
        other => panic!("{other:?}"),
    }
    let err = write_mesh_file(&dir.path("folder.ply/"), &tetrahedron(), MeshFormat::Obj);
    match err {
        Err(splash_sph::Error::Io { message, .. }) => {
            assert!(message.starts_with("cannot write '"), "{message}");
        }
        other => panic!("{other:?}"),
    }
}

/// Cutting or corrupting valid files anywhere gives errors (or particles), never a panic.
#[test]
fn damaged_files_never_panic() {
    let dir = TempDir::new("damaged");
    let originals = input_files(&dir);
    // One file per reader path: binary with skipped elements, binary with lists, ascii with
    // lists, CSV with a header, raw.
    for name in [
        "odd-Le.ply",
        "list-Be.ply",
        "list-Ascii.ply",
        "header-crlf.csv",
        "particles.bin",
    ] {
        let original = originals.iter().find(|p| p.ends_with(name)).unwrap();
        let bytes = fs::read(original).unwrap();
        let mut variants: Vec<Vec<u8>> =
            (0..bytes.len()).map(|len| bytes[..len].to_vec()).collect();
        for (i, junk) in (0..bytes.len()).zip([0xff, 0x00, b'\n', b'-', 0x80].iter().cycle()) {
            let mut corrupt = bytes.clone();
            corrupt[i] = *junk;
            variants.push(corrupt);
        }
        for (i, variant) in variants.iter().enumerate() {
            let damaged = dir.file(&format!("damaged-{i}-{name}"), variant);
            let _ = read_particles(&damaged, None);
        }
    }
}

/// The value a test file holds in property `k` of particle `i`: exact in every type used, and
/// different for every property and particle.
fn value(ty: &str, k: usize, i: usize) -> f64 {
    let whole = (3 * k + i) as f64;
    if matches!(ty, "float" | "double") {
        whole + 0.25
    } else {
        whole
    }
}

/// A PLY file of `n` particles with the vertex properties `props` (type, name) holding
/// [`value`]s; returns it with the values of each scalar property by name.
fn valued_ply(
    encoding: Encoding,
    props: &[(&str, &str)],
    n: usize,
) -> (Vec<u8>, BTreeMap<String, Vec<f32>>) {
    let format = match encoding {
        Encoding::Ascii => "ascii",
        Encoding::Le => "binary_little_endian",
        Encoding::Be => "binary_big_endian",
    };
    let mut header = format!("ply\nformat {format} 1.0\nelement vertex {n}\n");
    for (ty, name) in props {
        let ty = if *ty == "list" { "list uchar int" } else { ty };
        writeln!(header, "property {ty} {name}").unwrap();
    }
    header += "end_header\n";
    let mut out = header.into_bytes();
    let mut values: BTreeMap<String, Vec<f32>> = BTreeMap::new();
    for i in 0..n {
        for (k, (ty, name)) in props.iter().enumerate() {
            encode(ty, value(ty, k, i), encoding, &mut out);
            if *ty != "list" {
                let column = values.entry((*name).to_owned()).or_default();
                column.push(value(ty, k, i) as f32);
            }
        }
        if let Encoding::Ascii = encoding {
            out.push(b'\n');
        }
    }
    (out, values)
}

/// The particles `values` (by column name; none without particles) make with the given scalar
/// and vector attributes.
fn expected(
    values: &BTreeMap<String, Vec<f32>>,
    scalars: &[&str],
    vectors: &[(&str, [&str; 3])],
) -> Particles {
    let column = |name: &str| match values.get(name) {
        Some(column) => column.clone(),
        None if values.is_empty() => Vec::new(),
        None => panic!("no column '{name}' in {values:?}"),
    };
    let triples = |[a, b, c]: [&str; 3]| -> Vec<Vec3> {
        let [a, b, c] = [a, b, c].map(column);
        (0..a.len()).map(|i| Vec3::new(a[i], b[i], c[i])).collect()
    };
    let mut attributes = BTreeMap::new();
    for name in scalars {
        let column = column(name);
        attributes.insert((*name).to_owned(), Attribute::Scalar(column));
    }
    for (name, columns) in vectors {
        attributes.insert((*name).to_owned(), Attribute::Vector(triples(*columns)));
    }
    Particles {
        positions: triples(["x", "y", "z"]),
        attributes,
    }
}

/// Vector triples in any order and of mixed types, and scalars of every kind.
const MIXED: &[(&str, &str)] = &[
    ("uchar", "flag"),
    ("float", "vz"),
    ("double", "x"),
    ("int", "id"),
    ("float", "vx"),
    ("float", "y"),
    ("double", "vy"),
    ("float", "nz"),
    ("float", "z"),
    ("double", "density"),
    ("uchar", "nx"),
    ("float", "ny"),
    ("float", "foo_x"),
    ("int", "foo_y"),
    ("double", "foo_z"),
];
const MIXED_SCALARS: &[&str] = &["density", "flag", "id"];
const MIXED_VECTORS: &[(&str, [&str; 3])] = &[
    ("velocity", ["vx", "vy", "vz"]),
    ("normal", ["nx", "ny", "nz"]),
    ("foo", ["foo_x", "foo_y", "foo_z"]),
];

#[test]
fn ply_files_yield_every_attribute() {
    let dir = TempDir::new("ply-attributes");
    // A list property makes the binary records vary in size: another reader path.
    let mut with_list = MIXED.to_vec();
    with_list.insert(4, ("list", "neighbours"));
    for encoding in [Encoding::Ascii, Encoding::Le, Encoding::Be] {
        for (layout, props) in [("fixed", MIXED), ("list", &with_list[..])] {
            let (bytes, values) = valued_ply(encoding, props, 5);
            let path = dir.file(&format!("{layout}-{encoding:?}.ply"), bytes);
            let read = splash_sph::read_particles(&path, None).unwrap();
            let want = expected(&values, MIXED_SCALARS, MIXED_VECTORS);
            assert_eq!(read, want, "{}", path.display());
        }
    }
    // Without vertices, the attributes are there, empty.
    let (bytes, values) = valued_ply(Encoding::Le, MIXED, 0);
    let read = splash_sph::read_particles(&dir.file("empty.ply", bytes), None).unwrap();
    assert_eq!(read, expected(&values, MIXED_SCALARS, MIXED_VECTORS));
    assert_eq!(read.attributes.len(), 6);
}

#[test]
fn triples_are_vectors_unless_their_name_is_taken() {
    let names = [
        "velocity_z",
        "x",
        "velocity_x",
        "y",
        "velocity_y",
        "z",
        // `velocity` is taken by the triple before.
        "vx",
        "vy",
        "vz",
        // `normal` is a property.
        "normal",
        "nx",
        "ny",
        "nz",
        // `x` is a property.
        "x_x",
        "x_y",
        "x_z",
        // Incomplete, nameless, or not lower case (PLY names are case-sensitive).
        "bar_x",
        "bar_y",
        "_x",
        "_y",
        "_z",
        "VX",
        "VY",
        "VZ",
    ];
    let props: Vec<(&str, &str)> = names.iter().map(|&name| ("float", name)).collect();
    let (bytes, values) = valued_ply(Encoding::Ascii, &props, 3);
    let dir = TempDir::new("triples");
    let read = splash_sph::read_particles(&dir.file("triples.ply", bytes), None).unwrap();
    let vector = ["velocity_x", "velocity_y", "velocity_z"];
    let scalars: Vec<&str> = names
        .into_iter()
        .filter(|name| !["x", "y", "z"].contains(name) && !vector.contains(name))
        .collect();
    assert_eq!(read, expected(&values, &scalars, &[("velocity", vector)]));
}

#[test]
fn text_tables_with_a_header_yield_every_numeric_column() {
    let dir = TempDir::new("csv-attributes");
    let rows = 4;
    let columns = |names: &[&str]| -> BTreeMap<String, Vec<f32>> {
        let column = |k: usize| (0..rows).map(|i| value("float", k, i) as f32).collect();
        (names.iter().enumerate())
            .map(|(k, name)| (name.to_ascii_lowercase(), column(k)))
            .collect()
    };
    // `extra` columns follow, each row's with `{i}` replaced by the row's number.
    let table = |names: &[&str], separator: &str, extra: [&str; 2]| {
        let mut text = names.join(separator) + extra[0] + "\n";
        for i in 0..rows {
            let row: Vec<String> = (0..names.len())
                .map(|k| (value("float", k, i) as f32).to_string())
                .collect();
            text += &(row.join(separator) + &extra[1].replace("{i}", &i.to_string()) + "\n");
        }
        text
    };

    // Comma separated, any case and order; a text column and a repeated name are skipped.
    let names = ["id", "Z", "vx", "y", "X", "VY", "vz", "rho"];
    let text = table(&names, ",", [",name,RHO", ",p{i},9"]);
    let read = splash_sph::read_particles(&dir.file("comma.csv", &text), None).unwrap();
    let velocity = ("velocity", ["vx", "vy", "vz"]);
    let want = expected(&columns(&names), &["id", "rho"], &[velocity]);
    assert_eq!(read, want, "{text}");

    // Whitespace separated; a vector keeps the name its x column spells.
    let names = [
        "x",
        "y",
        "z",
        "velocity_x",
        "velocity_y",
        "velocity_z",
        "density",
        "Foo_X",
        "foo_y",
        "FOO_Z",
    ];
    let text = table(&names, " \t", ["", ""]);
    let read = splash_sph::read_particles(&dir.file("spaces.txt", &text), None).unwrap();
    let values = columns(&names);
    let velocity = ("velocity", ["velocity_x", "velocity_y", "velocity_z"]);
    let mut want = expected(&values, &["density"], &[velocity]);
    let foo = expected(&values, &[], &[("Foo", ["foo_x", "foo_y", "foo_z"])]);
    want.attributes.extend(foo.attributes);
    assert_eq!(read, want, "{text}");

    // No header: positions only.
    let read = splash_sph::read_particles(&dir.file("plain.csv", "1,2,3,4,5\n"), None).unwrap();
    assert_eq!(read.positions, [Vec3::new(1.0, 2.0, 3.0)]);
    assert!(read.attributes.is_empty());

    // A header without rows: its columns are attributes without values.
    let path = dir.file("header.csv", "x,y,z,vx,vy,vz,rho\n");
    let read = splash_sph::read_particles(&path, None).unwrap();
    assert_eq!(read.attributes["velocity"], Attribute::Vector(Vec::new()));
    assert_eq!(read.attributes["rho"], Attribute::Scalar(Vec::new()));

    // A column that holds numbers must hold them in every row.
    assert_fails(
        &dir.file("word.csv", "x,y,z,rho\n1,2,3,4\n1,2,3,high\n"),
        None,
        &["line 3, column 4 ('rho'): 'high' is not a number"],
    );
    assert_fails(
        &dir.file("short.csv", "x,y,z,rho\n1,2,3,4\n1,2,3\n"),
        None,
        &["line 3: the row has only 3 columns; missing column 4 ('rho')"],
    );
}

/// A PLY file written by ply_rs_bw, in `encoding`, with a face element after the vertices.
fn independent_ply(encoding: PlyEncoding, n: usize) -> Vec<u8> {
    let mut ply = Ply::<DefaultElement>::new();
    ply.header.encoding = encoding;
    let mut vertex = ElementDef::new("vertex".to_owned());
    let types = [
        ("x", ScalarType::Float),
        ("y", ScalarType::Float),
        ("z", ScalarType::Float),
        ("velocity_x", ScalarType::Double),
        ("velocity_y", ScalarType::Double),
        ("velocity_z", ScalarType::Double),
        ("density", ScalarType::Float),
        ("flag", ScalarType::UChar),
        ("id", ScalarType::Int),
    ];
    for (name, ty) in &types {
        let def = PropertyDef::new((*name).to_owned(), PropertyType::Scalar(ty.clone()));
        vertex.properties.add(def);
    }
    ply.header.elements.add(vertex);
    let mut face = ElementDef::new("face".to_owned());
    let list = PropertyType::List(ScalarType::UChar, ScalarType::Int);
    face.properties
        .add(PropertyDef::new("vertex_indices".to_owned(), list));
    ply.header.elements.add(face);
    let vertices = (0..n)
        .map(|i| {
            let mut e = DefaultElement::new();
            for (k, (name, ty)) in types.iter().enumerate() {
                // Exact as f32, and different for every property and particle.
                let v = ((i * types.len() + k) as f32 * 0.37).sin() * 10.0;
                let property = match ty {
                    ScalarType::Float => Property::Float(v),
                    ScalarType::Double => Property::Double(f64::from(v)),
                    ScalarType::UChar => Property::UChar((i + k) as u8),
                    _ => Property::Int(-((i * k) as i32)),
                };
                e.insert((*name).to_owned(), property);
            }
            e
        })
        .collect();
    ply.payload.insert("vertex".to_owned(), vertices);
    let mut face = DefaultElement::new();
    face.insert(
        "vertex_indices".to_owned(),
        Property::ListInt(vec![0, 1, 2]),
    );
    ply.payload.insert("face".to_owned(), vec![face]);
    let mut out = Vec::new();
    Writer::new().write_ply(&mut out, &mut ply).unwrap();
    out
}

/// The vertices of a PLY file as ply_rs_bw reads them: every scalar property as `f32`.
fn ply_rs_columns(bytes: &[u8]) -> BTreeMap<String, Vec<f32>> {
    let ply = Parser::<DefaultElement>::new()
        .read_ply(&mut &bytes[..])
        .unwrap();
    let mut columns: BTreeMap<String, Vec<f32>> = BTreeMap::new();
    for vertex in &ply.payload["vertex"] {
        for (name, property) in vertex {
            let value = match property {
                Property::Float(v) => *v,
                Property::Double(v) => *v as f32,
                Property::UChar(v) => f32::from(*v),
                Property::Int(v) => *v as f32,
                other => panic!("{name}: {other:?}"),
            };
            columns.entry(name.clone()).or_default().push(value);
        }
    }
    columns
}

#[test]
fn ply_files_of_an_independent_writer_read_back_equal() {
    let dir = TempDir::new("ply-rs");
    for encoding in [
        PlyEncoding::Ascii,
        PlyEncoding::BinaryLittleEndian,
        PlyEncoding::BinaryBigEndian,
    ] {
        let bytes = independent_ply(encoding, 6);
        let values = ply_rs_columns(&bytes);
        let path = dir.file(&format!("{encoding:?}.ply"), &bytes);
        let read = splash_sph::read_particles(&path, None).unwrap();
        let vector = ("velocity", ["velocity_x", "velocity_y", "velocity_z"]);
        let want = expected(&values, &["density", "flag", "id"], &[vector]);
        assert_eq!(read, want, "{encoding:?}");
        assert_eq!(read.len(), 6);
    }
}

#[test]
fn the_real_fixture_has_velocity_and_density() {
    let path = common::fixture("frame_0040.ply");
    let read = splash_sph::read_particles(&path, None).unwrap();
    let values = ply_rs_columns(&fs::read(&path).unwrap());
    let want = expected(&values, &["density"], &[("velocity", ["vx", "vy", "vz"])]);
    assert_eq!(read.attributes.len(), 2);
    let Attribute::Vector(velocity) = &read.attributes["velocity"] else {
        panic!("velocity is not a vector");
    };
    assert_eq!(velocity.len(), 44_064);
    // A fluid in motion, at about water's rest density.
    assert!(velocity.iter().any(|v| v.length() > 0.5));
    let Attribute::Scalar(density) = &read.attributes["density"] else {
        panic!("density is not a scalar");
    };
    let mean = density.iter().sum::<f32>() / density.len() as f32;
    assert!((900.0..1100.0).contains(&mean), "mean density {mean}");
    assert_eq!(read, want);
}

#[test]
fn truncated_files_with_attributes_are_reported() {
    let dir = TempDir::new("cut-attributes");
    let mut with_list = MIXED.to_vec();
    with_list.insert(4, ("list", "neighbours"));
    for (name, props) in [("fixed", MIXED), ("list", &with_list[..])] {
        let (bytes, _) = valued_ply(Encoding::Le, props, 5);
        // Inside the fourth of five records, which are all of one size.
        let payload_start = header_bytes(&bytes);
        let record = (bytes.len() - payload_start) / 5;
        let cut = payload_start + 3 * record + record / 2;
        let path = dir.file(&format!("{name}.ply"), &bytes[..cut]);
        let expected = if name == "fixed" {
            "after 3 complete vertex records"
        } else {
            "inside vertex record 3 of 5"
        };
        assert_fails(
            &path,
            None,
            &["truncated", &format!("byte offset {cut}"), expected],
        );
    }
    let (bytes, _) = valued_ply(Encoding::Ascii, MIXED, 5);
    let text = String::from_utf8(bytes).unwrap();
    let cut: String = text
        .split_inclusive('\n')
        .take(text.lines().count() - 2)
        .collect();
    let path = dir.file("ascii.ply", cut);
    assert_fails(&path, None, &["after 3 of 5 vertices"]);
}

/// The length of a PLY file's header.
fn header_bytes(bytes: &[u8]) -> usize {
    bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11
}

/// A tetrahedron with per-vertex normals.
fn tetrahedron() -> TriMesh {
    let vertices = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.5, 0.0, 0.0),
        Vec3::new(0.0, 0.1, 0.0),
        Vec3::new(0.0, 0.0, -2.25),
    ];
    let normals = vertices
        .iter()
        .map(|v| (*v - Vec3::new(0.3, 0.03, -0.5)).normalize())
        .collect();
    TriMesh {
        vertices,
        normals,
        triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
    }
}

fn mesh_bytes(mesh: &TriMesh, format: MeshFormat) -> Vec<u8> {
    let mut out = Vec::new();
    write_mesh(mesh, format, &mut out).unwrap();
    out
}

#[test]
fn obj_reads_back_with_tobj() {
    let dir = TempDir::new("obj");
    for mesh in [
        tetrahedron(),
        TriMesh {
            normals: Vec::new(),
            ..tetrahedron()
        },
    ] {
        let path = dir.path("mesh.obj");
        write_mesh_file(&path, &mesh, MeshFormat::Obj).unwrap();
        let options = tobj::LoadOptions {
            single_index: true,
            ..Default::default()
        };
        let (models, _) = tobj::load_obj(&path, &options).unwrap();
        assert_eq!(models.len(), 1);
        let read = &models[0].mesh;
        let corners: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
        assert_eq!(read.indices.len(), corners.len());
        // tobj renumbers vertices in order of first use, so compare corner by corner.
        for (&i, &j) in corners.iter().zip(&read.indices) {
            let (i, j) = (i as usize, j as usize);
            assert_eq!(Vec3::from_slice(&read.positions[3 * j..]), mesh.vertices[i]);
            if mesh.normals.is_empty() {
                assert!(read.normals.is_empty());
            } else {
                assert_eq!(Vec3::from_slice(&read.normals[3 * j..]), mesh.normals[i]);
            }
        }
    }
}

fn float(p: &Property) -> f32 {
    match p {
        Property::Float(v) => *v,
        other => panic!("not a float: {other:?}"),
    }
}

#[test]
fn ply_reads_back_in_both_encodings() {
    let dir = TempDir::new("ply-out");
    let mesh = tetrahedron();
    for format in [MeshFormat::PlyBinary, MeshFormat::PlyAscii] {
        let bytes = mesh_bytes(&mesh, format);
        let ply = Parser::<DefaultElement>::new()
            .read_ply(&mut bytes.as_slice())
            .unwrap();
        let vertices = &ply.payload["vertex"];
        assert_eq!(vertices.len(), mesh.vertices.len());
        for ((read, v), n) in vertices.iter().zip(&mesh.vertices).zip(&mesh.normals) {
            let xyz = Vec3::new(float(&read["x"]), float(&read["y"]), float(&read["z"]));
            let normal = Vec3::new(float(&read["nx"]), float(&read["ny"]), float(&read["nz"]));
            assert_eq!((xyz, normal), (*v, *n), "{format:?}");
        }
        let faces: Vec<[u32; 3]> = ply.payload["face"]
            .iter()
            .map(|f| match &f["vertex_indices"] {
                Property::ListInt(l) => [l[0], l[1], l[2]].map(|i| i as u32),
                other => panic!("not a list of int: {other:?}"),
            })
            .collect();
        assert_eq!(faces, mesh.triangles, "{format:?}");

        // The particle reader accepts meshes too: their vertices.
        let path = dir.file("mesh.ply", &bytes);
        assert_eq!(read_particles(&path, None).unwrap(), mesh.vertices);
    }
    let text = String::from_utf8(mesh_bytes(&mesh, MeshFormat::PlyAscii)).unwrap();
    assert!(
        text.contains("property list uchar int vertex_indices\n"),
        "{text}"
    );
    assert!(text.contains("\n3 0 2 1\n"), "{text}");
}

#[test]
fn invalid_meshes_are_not_written() {
    let mut out = Vec::new();
    let bad_index = TriMesh {
        triangles: vec![[0, 1, 2], [1, 9, 2]],
        ..tetrahedron()
    };
    let err = write_mesh(&bad_index, MeshFormat::Obj, &mut out).unwrap_err();
    assert!(
        err.to_string().contains("triangle 1 refers to vertex 9"),
        "{err}"
    );
    let mut bad_normals = tetrahedron();
    bad_normals.normals.pop();
    let err = write_mesh(&bad_normals, MeshFormat::PlyBinary, &mut out).unwrap_err();
    assert!(
        err.to_string().contains("3 normals for 4 vertices"),
        "{err}"
    );
    assert!(out.is_empty());
}

#[test]
fn mesh_files_are_replaced_atomically() {
    let dir = TempDir::new("atomic");
    let mesh = tetrahedron();

    let nested = dir.path("a/b/mesh.ply");
    write_mesh_file(&nested, &mesh, MeshFormat::PlyBinary).unwrap();
    assert_eq!(
        fs::read(&nested).unwrap(),
        mesh_bytes(&mesh, MeshFormat::PlyBinary)
    );

    // A shorter file replaces a longer one whole.
    let path = dir.file("mesh.obj", vec![b'#'; 100_000]);
    write_mesh_file(&path, &mesh, MeshFormat::Obj).unwrap();
    assert_eq!(fs::read(&path).unwrap(), mesh_bytes(&mesh, MeshFormat::Obj));

    // A failure after the temporary file exists leaves the old file.
    let bad = TriMesh {
        triangles: vec![[0, 1, 7]],
        ..tetrahedron()
    };
    let err = write_mesh_file(&path, &bad, MeshFormat::Obj).unwrap_err();
    assert!(err.to_string().contains("mesh.obj"), "{err}");
    assert_eq!(fs::read(&path).unwrap(), mesh_bytes(&mesh, MeshFormat::Obj));

    // The parent is a file.
    dir.file("plain-file", "x");
    let err = write_mesh_file(&dir.path("plain-file/mesh.obj"), &mesh, MeshFormat::Obj)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("plain-file/mesh.obj") && err.contains("directory"),
        "{err}"
    );

    // The target is a directory: the rename fails.
    fs::create_dir(dir.path("taken.ply")).unwrap();
    let err = write_mesh_file(&dir.path("taken.ply"), &mesh, MeshFormat::PlyAscii)
        .unwrap_err()
        .to_string();
    assert!(err.contains("taken.ply") && err.contains("rename"), "{err}");
    assert!(dir.path("taken.ply").is_dir());

    assert_eq!(dir.entries(), ["a", "mesh.obj", "plain-file", "taken.ply"]);
}

/// Reads a frame of the shared data set, if it is there.
fn real_frame(relative: &str) -> Option<(Vec<Vec3>, Duration)> {
    let path = common::shared_data(relative)?;
    let start = Instant::now();
    let particles = read_particles(&path, None).unwrap();
    Some((particles, start.elapsed()))
}

#[test]
fn reads_a_real_frame() {
    let Some((particles, _)) = real_frame("cbd-small/frame_0040.ply") else {
        return;
    };
    assert_eq!(particles.len(), 44_064);
    assert!(particles.iter().all(|p| p.is_finite()));
}

#[test]
fn reads_a_million_particles() {
    let Some((particles, elapsed)) = real_frame("cbd-large/frame_0023.ply") else {
        return;
    };
    println!("read {} particles in {elapsed:?}", particles.len());
    assert_eq!(particles.len(), 1_054_872);
    assert!(particles.iter().all(|p| p.is_finite()));
}

/// What a careful reader refuses rather than reading part of a file (issue 14, item 7): a
/// vertex count smaller than the data, extra values on a vertex line, a PLY version that does
/// not exist, and a coordinate column named twice.
#[test]
fn counts_lines_versions_and_columns_that_do_not_add_up_are_refused() {
    let dir = TempDir::new("careful");
    let le = |v: [f32; 3]| v.iter().flat_map(|c| c.to_le_bytes()).collect::<Vec<u8>>();
    let records: Vec<u8> = [[0.0, 1.0, 2.0], [3.0, 4.0, 5.0], [6.0, 7.0, 8.0]]
        .into_iter()
        .flat_map(le)
        .collect();
    let binary = |count: usize, tail: &[u8]| {
        let mut bytes = header("binary_little_endian", &count.to_string(), XYZ_PROPS).into_bytes();
        bytes.extend_from_slice(&records);
        bytes.extend_from_slice(tail);
        bytes
    };
    // The three records read whole; a final newline is tolerated, a fourth record is not.
    assert_eq!(
        read_particles(&dir.file("three.ply", binary(3, b"\n")), None)
            .unwrap()
            .len(),
        3
    );
    let short = dir.file("short.ply", binary(2, b""));
    assert_fails(
        &short,
        None,
        &["declares 2 vertices", "vertex count is too small"],
    );
    let ascii = |count: usize, body: &str| header("ascii", &count.to_string(), XYZ_PROPS) + body;
    let body = "0 1 2\n3 4 5\n6 7 8\n";
    assert_eq!(
        read_particles(&dir.file("three.txt.ply", ascii(3, body)), None)
            .unwrap()
            .len(),
        3
    );
    let short = dir.file("short_ascii.ply", ascii(2, body));
    assert_fails(&short, None, &["line 10", "more data after the 2 vertices"]);
    let long_line = dir.file("long_line.ply", ascii(3, "0 1 2\n3 4 5 9\n6 7 8\n"));
    assert_fails(
        &long_line,
        None,
        &["line 9", "more values than the 3 properties", "'9'"],
    );
    let version = header("ascii", "1", XYZ_PROPS).replace(" 1.0\n", " 2.0\n") + "0 1 2\n";
    let version = dir.file("version.ply", version);
    assert_fails(&version, None, &["version 2.0 is not supported"]);
    let twice = dir.file("twice.csv", "x,x,y,z\n1,2,3,4\n");
    assert_fails(&twice, None, &["line 1", "column 'x' 2 times"]);
}

/// A text file without line breaks is refused at the line limit, not read whole, and error
/// messages quote short excerpts of the file (issue 14, items 4 and 10).
#[test]
fn text_without_line_breaks_gives_a_short_error() {
    let dir = TempDir::new("no-breaks");
    let zeros = dir.file("zeros.csv", vec![0u8; 3 << 20]);
    assert_fails(&zeros, None, &["line 1 is longer than 1 MiB"]);
    let carriage_returns = "x;y;z\r1;2;3\r".repeat(1000);
    let cr = dir.file("cr.csv", &carriage_returns);
    let message = read_particles(&cr, None).unwrap_err().to_string();
    assert!(message.len() < 600, "{} bytes: {message}", message.len());
    let mut wide = (0..500)
        .map(|i| format!("c{i}"))
        .collect::<Vec<_>>()
        .join(",");
    wide.push('\n');
    let wide = dir.file("wide.csv", wide + &"1,".repeat(499) + "1\n");
    assert_fails(&wide, None, &["no column 'x'", "c0, c1", "… 488 more"]);
    let long = dir.file(
        "long.ply",
        header("ascii", "1", XYZ_PROPS) + &"8a".repeat(500) + " 1 2\n",
    );
    assert_fails(&long, None, &["cannot parse '", "…' as property 'x'"]);
    // An extra value on a vertex line is quoted by its start (found by tests/fuzz.rs: a line
    // ending in 3000 commas was quoted whole).
    let extra = dir.file(
        "extra.ply",
        header("ascii", "1", XYZ_PROPS) + "1 2 3 " + &",".repeat(3000) + "\n",
    );
    assert_fails(
        &extra,
        None,
        &["more values than the 3 properties", "…' on)"],
    );
    let message = read_particles(&extra, None).unwrap_err().to_string();
    assert!(message.len() < 300, "{message}");
    let message = read_particles(&long, None).unwrap_err().to_string();
    assert!(message.len() < 300, "{message}");
}

/// A malformed PLY header line is quoted by its start only: the parser's message quoted the
/// whole line, up to the header's megabyte (found by the fuzz harness, tests/fuzz.rs).
#[test]
fn a_long_malformed_header_line_gives_a_short_error() {
    let dir = TempDir::new("long-header-line");
    for line in [
        "element vert".to_string() + &",".repeat(70_000),
        "9".repeat(3000),
    ] {
        let text = format!("ply\nformat ascii 1.0\n{line}\n{XYZ_PROPS}end_header\n1 2 3\n");
        let path = dir.file("long.ply", text);
        assert_fails(&path, None, &["malformed PLY header", "line 3", "…"]);
        let message = read_particles(&path, None).unwrap_err().to_string();
        let own = message.len() - path.to_string_lossy().len();
        assert!(own < 300, "{} bytes: {message}", message.len());
    }
}

/// Element and property names are quoted by their start: a header's names may be as long as
/// the header (found by tests/fuzz.rs: a 1500-character element name was quoted whole).
#[test]
fn long_names_in_a_header_are_quoted_short() {
    let dir = TempDir::new("long-names");
    let long = "n".repeat(3000);
    let le = "binary_little_endian";
    let cases = [
        (
            format!(
                "ply\nformat {le} 1.0\nelement m{long} 2\nproperty list uchar float rgb\nelement vertex 0\n{XYZ_PROPS}end_header\n\x03"
            ),
            "truncated",
        ),
        (
            header(
                "ascii",
                "0",
                &format!("property list float int {long}\n{XYZ_PROPS}"),
            ),
            "non-integer length",
        ),
        (
            header("ascii", "1", &format!("property float {long}\n{XYZ_PROPS}")) + "a 1 2 3\n",
            "cannot parse 'a'",
        ),
        (
            header(
                "ascii",
                "1",
                &format!("property list uchar int {long}\n{XYZ_PROPS}"),
            ) + "a 1 2 3\n",
            "invalid list length 'a'",
        ),
        (
            header(
                le,
                "1",
                &format!("property list char int {long}\n{XYZ_PROPS}"),
            ) + "\u{80}", // 0xc2: -62 as a char
            "list length",
        ),
    ];
    for (i, (text, expected)) in cases.into_iter().enumerate() {
        let path = dir.file(&format!("long-{i}.ply"), text);
        assert_fails(&path, None, &[expected, "…"]);
        let message = read_particles(&path, None).unwrap_err().to_string();
        let own = message.len() - path.to_string_lossy().len();
        assert!(own < 300, "{} bytes: {message}", message.len());
    }
}

/// Column lists in CSV errors stay short: a short row names the first few missing columns,
/// each by the start of its name, and a header without `x` lists names up to a total length
/// (found by tests/fuzz.rs: a 70 kB column name, and twelve long names, were listed whole).
#[test]
fn csv_column_lists_in_errors_stay_short() {
    let dir = TempDir::new("csv-columns");
    let long = "d".repeat(70_000);
    let names: Vec<String> = (0..50).map(|i| format!("c{i}")).collect();
    let cases = [
        (
            format!("x,y,z,{long}\n1,2,3,4\n5\n"),
            vec![
                "line 3: the row has only 1 columns",
                "column 4 ('ddd",
                "…')",
            ],
        ),
        (
            format!(
                "x,y,z,{}\n{}\n1,2\n",
                names.join(","),
                vec!["1"; 53].join(",")
            ),
            vec!["missing column 3 ('z'), column 4 ('c0')", "and 47 more"],
        ),
        (
            format!("{}\n1\n", vec!["w".repeat(39); 12].join(",")),
            vec!["no column 'x'", "more)"],
        ),
    ];
    for (i, (text, expected)) in cases.into_iter().enumerate() {
        let path = dir.file(&format!("columns-{i}.csv"), text);
        let expected: Vec<&str> = expected.to_vec();
        assert_fails(&path, None, &expected);
        let message = read_particles(&path, None).unwrap_err().to_string();
        let own = message.len() - path.to_string_lossy().len();
        assert!(own < 300, "{own} bytes: {message}");
    }
}
