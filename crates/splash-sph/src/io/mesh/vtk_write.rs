//! VTK legacy output: `BINARY` `POLYDATA` (big-endian, as the format requires) with `POINTS`
//! (float), `POLYGONS` (triangles), and `POINT_DATA`: `NORMALS Normals` when the mesh has
//! normals, then each vertex attribute (`VECTORS name float` for vectors, `SCALARS name float 1`
//! for numbers). The version-3.0 layout, which ParaView, VTK 9 and meshio all read.

use std::io::{self, Write};

use super::failure::invalid_input;
use super::vertex_attributes::{AttributeValues, VertexAttributes};
use crate::data::TriMesh;

/// Payload bytes gathered before each write.
const BLOCK_BYTES: usize = 1 << 16;

/// `mesh` and `attributes` have been checked (one entry per vertex, indices in range).
pub(super) fn write(
    mesh: &TriMesh,
    attributes: &VertexAttributes,
    out: &mut impl Write,
) -> io::Result<()> {
    let n = mesh.vertices.len();
    let t = mesh.triangles.len();
    // POLYGONS counts its ints (4 per triangle) as an `int`.
    if i32::try_from(n).is_err() || t.checked_mul(4).is_none_or(|s| i32::try_from(s).is_err()) {
        return Err(invalid_input(format!(
            "a legacy VTK mesh holds at most {} vertices and {} triangles, not {n} and {t}",
            i32::MAX,
            i32::MAX / 4
        )));
    }
    let arrays = attributes.arrays();
    for (name, _) in &arrays {
        if name.is_empty() || name.chars().any(|c| c.is_whitespace() || c.is_control()) {
            return Err(invalid_input(format!(
                "a legacy VTK array name cannot be empty or hold spaces: '{name}'"
            )));
        }
    }
    write!(
        out,
        "# vtk DataFile Version 3.0\nsplash mesh\nBINARY\nDATASET POLYDATA\nPOINTS {n} float\n"
    )?;
    let mut block = Vec::with_capacity(BLOCK_BYTES + 64);
    floats(
        mesh.vertices.iter().flat_map(|v| v.to_array()),
        &mut block,
        out,
    )?;
    write!(out, "\nPOLYGONS {t} {}\n", 4 * t)?;
    for tri in &mesh.triangles {
        block.extend_from_slice(&3i32.to_be_bytes());
        // Indices are below the vertex count, hence below i32::MAX.
        for i in tri {
            block.extend_from_slice(&i.to_be_bytes());
        }
        flush_full(&mut block, out)?;
    }
    out.write_all(&block)?;
    block.clear();
    writeln!(out)?;
    if mesh.normals.is_empty() && arrays.is_empty() {
        return Ok(());
    }
    writeln!(out, "POINT_DATA {n}")?;
    if !mesh.normals.is_empty() {
        writeln!(out, "NORMALS Normals float")?;
        floats(
            mesh.normals.iter().flat_map(|v| v.to_array()),
            &mut block,
            out,
        )?;
        writeln!(out)?;
    }
    for (name, values) in arrays {
        match values {
            AttributeValues::Scalar(s) => {
                writeln!(out, "SCALARS {name} float 1\nLOOKUP_TABLE default")?;
                floats(s.iter().copied(), &mut block, out)?;
            }
            AttributeValues::Vector(v) => {
                writeln!(out, "VECTORS {name} float")?;
                floats(v.iter().flat_map(|v| v.to_array()), &mut block, out)?;
            }
        }
        writeln!(out)?;
    }
    Ok(())
}

/// Writes `values` as big-endian `f32`s through `block`, which is left empty.
fn floats(
    values: impl Iterator<Item = f32>,
    block: &mut Vec<u8>,
    out: &mut impl Write,
) -> io::Result<()> {
    for x in values {
        block.extend_from_slice(&x.to_be_bytes());
        flush_full(block, out)?;
    }
    out.write_all(block)?;
    block.clear();
    Ok(())
}

fn flush_full(block: &mut Vec<u8>, out: &mut impl Write) -> io::Result<()> {
    if block.len() >= BLOCK_BYTES {
        out.write_all(block)?;
        block.clear();
    }
    Ok(())
}
