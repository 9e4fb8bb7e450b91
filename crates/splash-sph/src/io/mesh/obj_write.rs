//! Wavefront OBJ mesh output.

use std::io::{self, Write};

use glam::Vec3;

use crate::data::TriMesh;
use crate::io::text::float_text::{F32Text, IntText};
use crate::io::text::text_records::{each_record, write_chunks};

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
    let corners = bytemuck::cast_slice(&mesh.triangles);
    write_chunks(out, mesh.triangles.len(), |rows, buffer| {
        let mut text = IntText::new(corners, 1);
        each_record(rows, buffer, |i, line| {
            text.push_row(line, b"f ", i, b" ", infix, b"\n")
        });
    })
}

/// One `{key}x y z` line per vector.
fn vectors<const K: usize>(
    out: &mut impl Write,
    key: &[u8; K],
    vectors: &[Vec3],
) -> io::Result<()> {
    let values = bytemuck::cast_slice(vectors);
    write_chunks(out, vectors.len(), |rows, buffer| {
        let mut text = F32Text::new(values);
        each_record(rows, buffer, |i, line| {
            text.push_row(line, key, i, b" ", b"\n")
        });
    })
}
