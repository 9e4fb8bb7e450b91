//! Wavefront OBJ mesh output.

use std::io::{self, Write};

use glam::Vec3;

use super::float_text::{push_f32_row, push_int_row};
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
    let infix = (!mesh.normals.is_empty()).then_some(b"//");
    write_records(out, mesh.triangles.len(), |i, line| {
        let corners = mesh.triangles[i].map(|corner| u64::from(corner) + 1);
        push_int_row(line, b"f ", corners, b" ", infix, b"\n");
    })
}

/// One `{key}x y z` line per vector.
fn vectors<const K: usize>(
    out: &mut impl Write,
    key: &[u8; K],
    vectors: &[Vec3],
) -> io::Result<()> {
    write_records(out, vectors.len(), |i, line| {
        push_f32_row(line, key, vectors[i].to_array(), b" ", b"\n");
    })
}
