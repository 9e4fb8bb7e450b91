//! Wavefront OBJ mesh output.

use std::io::{self, Write};

use super::float_text::push_f32s;
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
    for (key, vectors) in [(&b"v "[..], &mesh.vertices), (b"vn ", &mesh.normals)] {
        write_records(out, vectors.len(), |i, line| {
            line.extend_from_slice(key);
            push_f32s(line, vectors[i].to_array(), b" ");
            line.push(b'\n');
        })?;
    }
    let with_normals = !mesh.normals.is_empty();
    write_records(out, mesh.triangles.len(), |i, line| {
        line.push(b'f');
        let mut text = itoa::Buffer::new();
        for corner in mesh.triangles[i] {
            let index = text.format(u64::from(corner) + 1).as_bytes();
            line.push(b' ');
            line.extend_from_slice(index);
            if with_normals {
                line.extend_from_slice(b"//");
                line.extend_from_slice(index);
            }
        }
        line.push(b'\n');
    })
}
