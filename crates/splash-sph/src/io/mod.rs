//! Reading particle frames and writing meshes.
//!
//! Particle inputs (see [`InputFormat`]), read in one pass with every per-particle attribute
//! the file has (see [`read_particles`]):
//! - PLY, ascii or binary (either byte order): the `vertex` element's `x`, `y`, `z` properties,
//!   of any scalar type and in any position; its other scalar properties are attributes, its
//!   list properties and the other elements are skipped.
//! - Text tables (`.csv`, `.txt`): see [`read_particles`] for the accepted dialect.
//! - Raw: little-endian `f32` `x y z` triples and nothing else.
//! - Legacy VTK (`.vtk`), ascii or binary: points and every `POINT_DATA` array.
//! - VTK XML (`.vtu`, `.vtp`): points and every `PointData` array, in every data mode and
//!   encoding, zlib-compressed or not.
//! - Classic BGEO (`.bgeo`, `.bgeo.gz`): positions and float, int and vector attributes.
//! - `.xyz`: raw `f32` triples, or a text table when the file is text.
//!
//! Arrays of width 1 are scalar attributes, width 3 vectors, and other widths one scalar per
//! component (`{name}_0`, …). Every count read from a file is checked against the bytes that
//! can hold it before anything is allocated; compressed data is inflated no further than its
//! header declares.
//!
//! Every reader error names the file and what is wrong with it, with the line (text) or byte
//! offset (binary) where that helps. Coordinates must be finite. A frame without particles is
//! valid and reads as empty `Vec`s.
//!
//! Meshes are written as OBJ, PLY (binary little-endian or ascii), POV-Ray `mesh2`, VTK legacy
//! binary, VTK XML (`.vtu`, `.vtp`) or USD text layers (`.usda`), atomically when written to a
//! file with [`write_mesh_file`]. PLY, VTK and USD files can carry per-vertex attributes
//! ([`VertexAttributes`]). [`read_mesh`] reads them back, but for POV-Ray's and USD's. A
//! sequence of USD layers plays as one animated mesh through a stage of value clips
//! ([`write_usd_stage`]).

#[macro_use]
mod failure;

pub(crate) mod atomic;
mod mesh_read;
mod obj;
mod obj_read;
mod particles;
mod ply_mesh;
mod ply_write;
mod pov;
mod text;
mod usd;
mod usd_stage;
mod vertex_attributes;
mod vtk_write;
mod vtu_write;

use std::io::{self, BufWriter, Write};
use std::path::Path;

use crate::data::TriMesh;
use failure::{invalid_input, listed, short};
pub use mesh_read::{MeshFile, read_mesh};
pub use particles::{InputFormat, read_particles};

#[doc(no_inline)]
pub use crate::data::{Attribute, MeshFormat, Particles, UpAxis};
pub use pov::POV_OBJECT;
pub use usd::{USD_PRIM, UsdFrame};
pub use usd_stage::{
    USD_FRAMES_PER_SECOND, UsdClip, usd_stage_path, usd_topology_path, write_usd_stage,
};
pub use vertex_attributes::VertexAttributes;

/// Writes `mesh` in `format`. `normals` must be empty or have one entry per vertex; without
/// normals, none are written.
pub fn write_mesh(mesh: &TriMesh, format: MeshFormat, w: &mut impl Write) -> io::Result<()> {
    write_mesh_with(mesh, &VertexAttributes::default(), format, w)
}

/// Writes `mesh` with per-vertex `attributes` (one entry per vertex each); formats without
/// room for an attribute refuse it.
pub fn write_mesh_with(
    mesh: &TriMesh,
    attributes: &VertexAttributes,
    format: MeshFormat,
    w: &mut impl Write,
) -> io::Result<()> {
    check_mesh(mesh)?;
    if !attributes.is_empty() && !format.holds_attributes() {
        let names: Vec<&str> = attributes.arrays().iter().map(|(n, _)| *n).collect();
        return Err(invalid_input(format!(
            ".{} files cannot hold vertex attributes ({}): write PLY, VTK, VTU, VTP or USD",
            format.extension(),
            listed(names)
        )));
    }
    check_attributes(mesh, attributes)?;
    let mut out = BufWriter::with_capacity(1 << 16, w);
    match format {
        MeshFormat::Obj => obj::write(mesh, &mut out)?,
        MeshFormat::PlyBinary => ply_write::write(mesh, attributes, false, &mut out)?,
        MeshFormat::PlyAscii => ply_write::write(mesh, attributes, true, &mut out)?,
        MeshFormat::Pov => pov::write(mesh, &mut out)?,
        MeshFormat::Vtk => vtk_write::write(mesh, attributes, &mut out)?,
        MeshFormat::Vtu => vtu_write::write(
            mesh,
            attributes,
            vtu_write::Kind::UnstructuredGrid,
            &mut out,
        )?,
        MeshFormat::Vtp => vtu_write::write(mesh, attributes, vtu_write::Kind::PolyData, &mut out)?,
        MeshFormat::Usd => usd::write(mesh, attributes, UsdFrame::default(), &mut out)?,
    }
    out.flush()
}

/// Writes a USD layer of `mesh` placed in time and space by `frame` (its values sampled at
/// the frame's time code, for a stage's value clips), whole or not at all, as
/// [`write_mesh_file`] does.
pub fn write_usd_file(
    path: &Path,
    mesh: &TriMesh,
    attributes: &VertexAttributes,
    frame: UsdFrame,
) -> crate::Result<()> {
    atomic::write_file(path, |file| {
        check_mesh(mesh)?;
        check_attributes(mesh, attributes)?;
        let mut out = BufWriter::with_capacity(1 << 16, file);
        usd::write(mesh, attributes, frame, &mut out)?;
        out.flush()
    })
}

/// Writes to a temporary file in the same directory, fsyncs, renames onto `path`; on any error
/// removes the temporary and leaves an existing `path` untouched. Creates missing parent
/// directories.
pub fn write_mesh_file(path: &Path, mesh: &TriMesh, format: MeshFormat) -> crate::Result<()> {
    write_mesh_file_with(path, mesh, &VertexAttributes::default(), format)
}

/// [`write_mesh_file`] with per-vertex attributes.
pub fn write_mesh_file_with(
    path: &Path,
    mesh: &TriMesh,
    attributes: &VertexAttributes,
    format: MeshFormat,
) -> crate::Result<()> {
    atomic::write_file(path, |file| write_mesh_with(mesh, attributes, format, file))
}

/// Rejects attributes without one value per vertex, and a name given twice.
fn check_attributes(mesh: &TriMesh, attributes: &VertexAttributes) -> io::Result<()> {
    let arrays = attributes.arrays();
    for (i, (name, values)) in arrays.iter().enumerate() {
        if values.len() != mesh.vertices.len() {
            return Err(invalid_input(format!(
                "mesh has {} values of '{}' for {} vertices",
                values.len(),
                short(name),
                mesh.vertices.len()
            )));
        }
        if arrays[..i].iter().any(|(n, _)| n == name) {
            return Err(invalid_input(format!(
                "the vertex attribute '{}' is given twice",
                short(name)
            )));
        }
    }
    Ok(())
}

/// Rejects meshes that would make a corrupt file rather than writing them.
fn check_mesh(mesh: &TriMesh) -> io::Result<()> {
    let invalid = |message: String| io::Error::new(io::ErrorKind::InvalidInput, message);
    if !mesh.normals.is_empty() && mesh.normals.len() != mesh.vertices.len() {
        return Err(invalid(format!(
            "mesh has {} normals for {} vertices",
            mesh.normals.len(),
            mesh.vertices.len()
        )));
    }
    let vertex_count = mesh.vertices.len();
    let out_of_range = mesh.triangles.iter().enumerate().find_map(|(t, corners)| {
        let bad = corners.iter().find(|&&i| i as usize >= vertex_count)?;
        Some((t, *bad))
    });
    if let Some((t, index)) = out_of_range {
        return Err(invalid(format!(
            "mesh triangle {t} refers to vertex {index}, but there are only {vertex_count} vertices"
        )));
    }
    Ok(())
}
