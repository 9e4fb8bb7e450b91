//! `io::read_mesh`: every mesh format it reads gives back, bit for bit, what the writer was
//! given (vertices, triangles, normals, attributes); files from elsewhere (big-endian PLY,
//! OBJ with negative indices) read too; broken files give errors naming the file, never a
//! panic, and a header's counts never allocate beyond the file.

use std::fs;
use std::path::{Path, PathBuf};

use glam::Vec3;
use splash_sph::io::{MeshFormat, VertexAttributes, read_mesh, write_mesh_file_with};
use splash_sph::mesh::TriMesh;
use splash_sph::{Attribute, Config, Error, Reconstructor};

/// A scratch directory of this test binary, emptied first.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("splash-read-mesh-{}-{name}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

/// A reconstructed ball of particles with velocity and density on its vertices.
fn ball() -> (TriMesh, Vec<(String, Attribute)>) {
    let mut particles = Vec::new();
    for i in -5..=5 {
        for j in -5..=5 {
            for k in -5..=5 {
                let p = Vec3::new(i as f32, j as f32, k as f32) * 0.1;
                if p.length() <= 0.5 {
                    particles.push(p);
                }
            }
        }
    }
    let config = Config {
        spacing: Some(0.1),
        ..Config::default()
    };
    let mesh = Reconstructor::new(config)
        .unwrap()
        .reconstruct(&particles)
        .unwrap()
        .mesh;
    assert!(mesh.triangles.len() > 100 && mesh.normals.len() == mesh.vertices.len());
    let velocity = mesh
        .vertices
        .iter()
        .map(|v| Vec3::new(v.y, -v.x, 0.3))
        .collect();
    let density = mesh.vertices.iter().map(|v| 1000.0 + v.z).collect();
    let attributes = vec![
        ("density".to_string(), Attribute::Scalar(density)),
        ("velocity".to_string(), Attribute::Vector(velocity)),
    ];
    (mesh, attributes)
}

#[test]
fn every_written_format_reads_back_bit_for_bit() {
    let dir = scratch("round-trip");
    let (mesh, attributes) = ball();
    let cases = [
        (MeshFormat::Obj, "f.obj"),
        (MeshFormat::PlyBinary, "f.ply"),
        (MeshFormat::PlyAscii, "ascii.ply"),
        (MeshFormat::Vtk, "f.vtk"),
        (MeshFormat::Vtu, "f.vtu"),
        (MeshFormat::Vtp, "f.vtp"),
    ];
    for (format, name) in cases {
        let path = dir.join(name);
        let named = if format.holds_attributes() {
            attributes.as_slice()
        } else {
            &[]
        };
        let with = VertexAttributes {
            velocities: None,
            named,
        };
        write_mesh_file_with(&path, &mesh, &with, format).unwrap();
        let back = read_mesh(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        let bits = |v: &[Vec3]| {
            v.iter()
                .map(|p| p.to_array().map(f32::to_bits))
                .collect::<Vec<_>>()
        };
        assert_eq!(bits(&back.mesh.vertices), bits(&mesh.vertices), "{name}");
        assert_eq!(bits(&back.mesh.normals), bits(&mesh.normals), "{name}");
        assert_eq!(back.mesh.triangles, mesh.triangles, "{name}");
        let expected: Vec<(String, Attribute)> = back.attributes.into_iter().collect();
        assert_eq!(expected, named, "{name}");
    }
    // Without normals, none come back.
    let bare = TriMesh {
        normals: Vec::new(),
        ..mesh.clone()
    };
    for (format, name) in cases {
        let path = dir.join(format!("bare-{name}"));
        write_mesh_file_with(&path, &bare, &VertexAttributes::default(), format).unwrap();
        let back = read_mesh(&path).unwrap();
        assert!(back.mesh.normals.is_empty(), "{name}");
        assert_eq!(back.mesh.triangles, mesh.triangles, "{name}");
    }
    // An empty mesh is a valid file.
    for (format, name) in cases {
        let path = dir.join(format!("empty-{name}"));
        write_mesh_file_with(
            &path,
            &TriMesh::default(),
            &VertexAttributes::default(),
            format,
        )
        .unwrap();
        assert_eq!(read_mesh(&path).unwrap().mesh, TriMesh::default(), "{name}");
    }
    let _ = fs::remove_dir_all(dir);
}

#[test]
fn meshes_from_other_writers_read() {
    let dir = scratch("other");
    // Big-endian PLY with double coordinates, an int list count and a comment.
    let mut ply = b"ply\nformat binary_big_endian 1.0\ncomment elsewhere\nelement vertex 3\n\
        property double x\nproperty double y\nproperty double z\nproperty float pressure\n\
        element face 1\nproperty list int uint vertex_indices\nend_header\n"
        .to_vec();
    for (i, p) in [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.5]]
        .iter()
        .enumerate()
    {
        for c in p {
            ply.extend_from_slice(&f64::to_be_bytes(*c));
        }
        ply.extend_from_slice(&(i as f32 * 2.0).to_be_bytes());
    }
    for v in [3i32, 0, 2, 1] {
        ply.extend_from_slice(&v.to_be_bytes());
    }
    fs::write(dir.join("be.ply"), &ply).unwrap();
    let back = read_mesh(&dir.join("be.ply")).unwrap();
    assert_eq!(back.mesh.vertices[2], Vec3::new(0.0, 1.0, 0.5));
    assert_eq!(back.mesh.triangles, vec![[0, 2, 1]]);
    assert_eq!(
        back.attributes["pressure"],
        Attribute::Scalar(vec![0.0, 2.0, 4.0])
    );
    // OBJ with comments, groups, texture corners and negative (relative) indices.
    let obj = "# elsewhere\no thing\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\ng part\ns 1\n\
               f 1/1 2/1 3/1\nf -3 -1 -2\n";
    fs::write(dir.join("o.obj"), obj).unwrap();
    let back = read_mesh(&dir.join("o.obj")).unwrap();
    assert_eq!(back.mesh.triangles, vec![[0, 1, 2], [0, 2, 1]]);
    assert!(back.mesh.normals.is_empty());
    let _ = fs::remove_dir_all(dir);
}

/// The content error of `path`, which must name it.
fn content_error(path: &Path) -> String {
    match read_mesh(path) {
        Err(e @ Error::MeshFormat { .. }) => {
            let message = e.to_string();
            let name = path.file_name().unwrap().to_str().unwrap();
            assert!(message.contains(name), "{message}");
            message
        }
        other => panic!("{}: expected a format error, got {other:?}", path.display()),
    }
}

#[test]
fn broken_files_are_errors_naming_the_file_and_the_fault() {
    let dir = scratch("broken");
    let header = "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\n\
                  property float x\nproperty float y\nproperty float z\nend_header\n";
    let cases: [(&str, &[u8], &str); 12] = [
        (
            "cut.ply",
            b"ply\nformat binary_little_endian 1.0\nelement vertex 10\n",
            "end_header",
        ),
        // Four billion vertices declared in a few bytes: refused before any allocation.
        ("huge.ply", header.as_bytes(), "too short"),
        (
            "quad.ply",
            b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
              property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
              end_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n",
            "not a triangle",
        ),
        (
            "edges.ply",
            b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
              property float z\nelement edge 0\nproperty int vertex1\nend_header\n0 0 0\n",
            "'vertex' and 'face'",
        ),
        (
            "quad.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3 4\n",
            "4 corners",
        ),
        (
            "far.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
            "refers to vertex 8 of 3",
        ),
        ("nan.obj", b"v 0 nan 0\n", "non-finite"),
        (
            "normals.obj",
            b"v 0 0 0\nv 1 0 0\nvn 0 0 1\n",
            "1 'vn' lines for 2 'v' lines",
        ),
        (
            "cut.vtu",
            b"<VTKFile type=\"UnstructuredGrid\"><Unstructured",
            "XML",
        ),
        (
            "quad.vtk",
            b"# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 4 float\n\
              0 0 0 1 0 0 1 1 0 0 1 0\nPOLYGONS 1 5\n4 0 1 2 3\n",
            "not all triangles",
        ),
        (
            "lines.vtk",
            b"# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 2 float\n\
              0 0 0 1 0 0\nLINES 1 3\n2 0 1\n",
            "triangles (POLYGONS) only",
        ),
        ("mesh.stl", b"solid x\nendsolid x\n", "extension"),
    ];
    for (name, content, fault) in cases {
        let path = dir.join(name);
        fs::write(&path, content).unwrap();
        let message = content_error(&path);
        assert!(message.contains(fault), "{name}: {message}");
    }
    match read_mesh(&dir.join("none.ply")) {
        Err(Error::Io {
            io_error, message, ..
        }) => {
            assert_eq!(io_error.kind(), std::io::ErrorKind::NotFound);
            assert!(message.contains("none.ply"), "{message}");
        }
        other => panic!("a missing file: {other:?}"),
    }
    let _ = fs::remove_dir_all(dir);
}

/// Bytes changed, cut and inserted (seeded): every reader returns a mesh or a format error
/// naming the file; none panics.
#[test]
fn mutated_files_never_panic() {
    let dir = scratch("mutated");
    let (mesh, attributes) = ball();
    let small = TriMesh {
        vertices: mesh.vertices[..60].to_vec(),
        normals: mesh.normals[..60].to_vec(),
        triangles: mesh
            .triangles
            .iter()
            .copied()
            .filter(|t| t.iter().all(|&i| i < 60))
            .collect(),
    };
    let few: Vec<(String, Attribute)> = attributes
        .into_iter()
        .map(|(name, a)| match a {
            Attribute::Scalar(s) => (name, Attribute::Scalar(s[..60].to_vec())),
            Attribute::Vector(v) => (name, Attribute::Vector(v[..60].to_vec())),
        })
        .collect();
    let mut state = 0x5eed_u64;
    let mut next = |below: usize| {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 33) as usize) % below.max(1)
    };
    for (format, name) in [
        (MeshFormat::Obj, "m.obj"),
        (MeshFormat::PlyBinary, "m.ply"),
        (MeshFormat::PlyAscii, "a.ply"),
        (MeshFormat::Vtk, "m.vtk"),
        (MeshFormat::Vtu, "m.vtu"),
        (MeshFormat::Vtp, "m.vtp"),
    ] {
        let seed = dir.join(format!("seed-{name}"));
        let named = if format.holds_attributes() {
            few.as_slice()
        } else {
            &[]
        };
        let with = VertexAttributes {
            velocities: None,
            named,
        };
        write_mesh_file_with(&seed, &small, &with, format).unwrap();
        let data = fs::read(&seed).unwrap();
        let path = dir.join(name);
        for _ in 0..300 {
            let mut d = data.clone();
            for _ in 0..1 + next(6) {
                if d.is_empty() {
                    break;
                }
                let i = next(d.len());
                match next(4) {
                    0 | 1 => d[i] = next(256) as u8,
                    2 => drop(d.drain(i..(i + 1 + next(50)).min(d.len()))),
                    _ => d.truncate(i),
                }
            }
            fs::write(&path, &d).unwrap();
            if read_mesh(&path).is_err() {
                content_error(&path);
            }
        }
    }
    let _ = fs::remove_dir_all(dir);
}
