//! Wavefront OBJ mesh output.

use std::io::{self, Write};

use glam::Vec3;

use super::float_text::{push_f32s, push_int, push_int_twice};
use super::text_records::write_records;
use crate::mesh::TriMesh;

/// Writes `v`, then `vn` lines, then 1-based `f` lines (`a//a` when there are normals), each
/// kind formatted on all threads. Coordinates are printed as `{}` prints them: the shortest text
/// that reads back as the same `f32`.
pub(super) fn write(mesh: &TriMesh, out: &mut impl Write) -> io::Result<()> {
    writeln!(
        out,
        "# splash mesh: {} vertices, {} triangles",
        mesh.vertices.len(),
        mesh.triangles.len()
    )?;
    vectors(out, b"v ", &mesh.vertices)?;
    vectors(out, b"vn ", &mesh.normals)?;
    let with_normals = !mesh.normals.is_empty();
    write_records(out, mesh.triangles.len(), |i, line| {
        line.push(b'f');
        for corner in mesh.triangles[i] {
            let index = u64::from(corner) + 1;
            if with_normals {
                push_int_twice(line, b' ', index, *b"//");
            } else {
                line.push(b' ');
                push_int(line, index);
            }
        }
        line.push(b'\n');
    })
}

/// One `{key}x y z` line per vector.
fn vectors<const K: usize>(
    out: &mut impl Write,
    key: &[u8; K],
    vectors: &[Vec3],
) -> io::Result<()> {
    write_records(out, vectors.len(), |i, line| {
        line.extend_from_slice(key);
        push_f32s(line, vectors[i].to_array(), b" ");
        line.push(b'\n');
    })
}
