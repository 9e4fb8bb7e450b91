//! POV-Ray output: an include file declaring the mesh as a `mesh2` object named
//! [`super::POV_OBJECT`], to be placed in a scene with `object { SplashMesh material { … } }`.
//!
//! POV-Ray's axes are left-handed; the coordinates are written as they are, so a scene sees the
//! simulation mirrored unless its camera says `right -x*image_width/image_height` (the README's
//! example does). Normals smooth the shading; `inside_vector` makes the closed mesh a solid, for
//! refraction, media and CSG. A mesh without triangles is declared as an empty `union`, which
//! POV-Ray accepts and renders as nothing, so every frame of a sequence has an include.

use std::io::{self, Write};

use crate::mesh::TriMesh;

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
    vectors(out, mesh.vertices.iter().map(|v| v.to_array()))?;
    if !mesh.normals.is_empty() {
        writeln!(out, "  normal_vectors {{\n    {},", mesh.normals.len())?;
        vectors(out, mesh.normals.iter().map(|v| v.to_array()))?;
    }
    writeln!(out, "  face_indices {{\n    {},", mesh.triangles.len())?;
    let last = mesh.triangles.len() - 1;
    for (i, [a, b, c]) in mesh.triangles.iter().enumerate() {
        let comma = if i < last { "," } else { "" };
        writeln!(out, "    <{a},{b},{c}>{comma}")?;
    }
    writeln!(out, "  }}")?;
    // Any direction works for a closed mesh; one that is not along an axis avoids grazing rays
    // along the grid's faces.
    writeln!(out, "  inside_vector <0.267, 0.535, 0.802>")?;
    writeln!(out, "}}")
}

/// The body of a `vertex_vectors` or `normal_vectors` block after its count, and its end.
/// `{}` prints the shortest text that reads back as the same `f32`, never in exponent form.
fn vectors(out: &mut impl Write, items: impl ExactSizeIterator<Item = [f32; 3]>) -> io::Result<()> {
    let last = items.len().saturating_sub(1);
    for (i, [x, y, z]) in items.enumerate() {
        let comma = if i < last { "," } else { "" };
        writeln!(out, "    <{x},{y},{z}>{comma}")?;
    }
    writeln!(out, "  }}")
}
