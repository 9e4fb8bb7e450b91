//! POV-Ray output: an include file declaring the mesh as a `mesh2` object named
//! [`super::POV_OBJECT`], to be placed in a scene with `object { SplashMesh material { … } }`.
//!
//! POV-Ray's axes are left-handed; the coordinates are written as they are, so a scene sees the
//! simulation mirrored unless its camera says `right -x*image_width/image_height` (the README's
//! example does). Normals smooth the shading; `inside_vector` makes the closed mesh a solid, for
//! refraction, media and CSG. A mesh without triangles is declared as an empty `union`, which
//! POV-Ray accepts and renders as nothing, so every frame of a sequence has an include.

use std::io::{self, Write};

use glam::Vec3;

use crate::data::TriMesh;
use crate::io::text::float_text::{F32Text, IntText};
use crate::io::text::text_records::{each_record, write_chunks};

/// The name a `--format pov` file declares its mesh under: `object { SplashMesh … }`.
pub const POV_OBJECT: &str = "SplashMesh";

pub(super) fn write(mesh: &TriMesh, out: &mut impl Write) -> io::Result<()> {
    writeln!(
        out,
        "// splash mesh: {} vertices, {} triangles",
        mesh.vertices.len(),
        mesh.triangles.len()
    )?;
    if mesh.triangles.is_empty() {
        return writeln!(out, "#declare {POV_OBJECT} = union {{}}");
    }
    writeln!(out, "#declare {POV_OBJECT} = mesh2 {{")?;
    writeln!(out, "  vertex_vectors {{\n    {},", mesh.vertices.len())?;
    vectors(out, &mesh.vertices)?;
    if !mesh.normals.is_empty() {
        writeln!(out, "  normal_vectors {{\n    {},", mesh.normals.len())?;
        vectors(out, &mesh.normals)?;
    }
    writeln!(out, "  face_indices {{\n    {},", mesh.triangles.len())?;
    let triangles = &mesh.triangles;
    let corners = bytemuck::cast_slice(triangles);
    write_chunks(out, triangles.len(), |rows, buffer| {
        let mut text = IntText::new(corners, 0);
        each_record(rows, buffer, |i, line| {
            text.push_row(line, b"    <", i, b",", None, b">");
            end(line, i, triangles.len());
        });
    })?;
    writeln!(out, "  }}")?;
    // Any direction works for a closed mesh; one that is not along an axis avoids grazing rays
    // along the grid's faces.
    writeln!(out, "  inside_vector <0.267, 0.535, 0.802>")?;
    writeln!(out, "}}")
}

/// The body of a `vertex_vectors` or `normal_vectors` block after its count, and its end.
/// Coordinates are printed as `{}` prints them: the shortest text that reads back as the same
/// `f32`, never in exponent form.
fn vectors(out: &mut impl Write, vectors: &[Vec3]) -> io::Result<()> {
    let values = bytemuck::cast_slice(vectors);
    write_chunks(out, vectors.len(), |rows, buffer| {
        let mut text = F32Text::new(values);
        each_record(rows, buffer, |i, line| {
            text.push_row(line, b"    <", i, b",", b">");
            end(line, i, vectors.len());
        });
    })?;
    writeln!(out, "  }}")
}

/// Ends item `i` of `count`: a comma but after the last.
fn end(line: &mut Vec<u8>, i: usize, count: usize) {
    if i + 1 < count {
        line.push(b',');
    }
    line.push(b'\n');
}
