//! Wavefront OBJ mesh output.

use std::io::{self, Write};

use crate::mesh::TriMesh;

/// Writes `v`, then `vn` lines, then 1-based `f` lines (`a//a` when there are normals). `{}`
/// prints the shortest text that reads back as the same `f32`.
pub(super) fn write(mesh: &TriMesh, out: &mut impl Write) -> io::Result<()> {
    writeln!(
        out,
        "# splash mesh: {} vertices, {} triangles",
        mesh.vertices.len(),
        mesh.triangles.len()
    )?;
    for v in &mesh.vertices {
        writeln!(out, "v {} {} {}", v.x, v.y, v.z)?;
    }
    for n in &mesh.normals {
        writeln!(out, "vn {} {} {}", n.x, n.y, n.z)?;
    }
    let with_normals = !mesh.normals.is_empty();
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| u64::from(i) + 1);
        if with_normals {
            writeln!(out, "f {a}//{a} {b}//{b} {c}//{c}")?;
        } else {
            writeln!(out, "f {a} {b} {c}")?;
        }
    }
    Ok(())
}
