//! Writing meshes, and reading back the ones splash writes. [`write_mesh`] and
//! [`write_mesh_file`] pick a writer by [`MeshFormat`], each `<format>_write.rs` writing one
//! format, with the per-vertex attributes of [`VertexAttributes`]; [`read_mesh`] (`read.rs`)
//! picks a reader by the file's extension. `vdb_write.rs` writes OpenVDB grids, which hold a
//! mesh's level set rather than the mesh (see [`crate::level_set`]); [`read_mesh`]: `obj_read.rs`, `ply_read.rs`, and for VTK files
//! the particle readers' `vtk_read` and `vtu_read`, which read a mesh's triangles too.

mod obj_read;
mod obj_write;
mod ply_read;
mod ply_write;
mod pov_write;
mod read;
mod usd_stage_write;
mod usd_write;
mod vdb_write;
mod vertex_attributes;
mod vtk_write;
mod vtu_write;

use std::io::{self, BufWriter, Write};
use std::path::Path;

use super::atomic;
// The readers' and writers' errors and helpers are io's (`super::failure`, `super::short`).
use super::failure::{self, invalid_input, listed, short};
use crate::data::{MeshFormat, TriMesh};
use crate::error::Result;
pub use pov_write::POV_OBJECT;
pub use read::{MeshFile, read_mesh};
pub(crate) use usd_stage_write::{
    USD_FRAMES_PER_SECOND, UsdClip, usd_stage_path, usd_topology_path, write_usd_stage,
};
pub use usd_write::USD_PRIM;
pub(crate) use usd_write::UsdFrame;
pub(crate) use vdb_write::{VdbGrid, VdbLeaf, VdbNode, VdbTree, VdbValues, write_vdb};
pub(crate) use vdb_write::{
    file_order as vdb_file_order, node_origin as vdb_node_origin, slot as vdb_slot,
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
        MeshFormat::Obj => obj_write::write(mesh, &mut out)?,
        MeshFormat::PlyBinary => ply_write::write(mesh, attributes, false, &mut out)?,
        MeshFormat::PlyAscii => ply_write::write(mesh, attributes, true, &mut out)?,
        MeshFormat::Pov => pov_write::write(mesh, &mut out)?,
        MeshFormat::Vtk => vtk_write::write(mesh, attributes, &mut out)?,
        MeshFormat::Vtu => vtu_write::write(
            mesh,
            attributes,
            vtu_write::Kind::UnstructuredGrid,
            &mut out,
        )?,
        MeshFormat::Vtp => vtu_write::write(mesh, attributes, vtu_write::Kind::PolyData, &mut out)?,
        MeshFormat::Usd => usd_write::write(mesh, attributes, UsdFrame::default(), &mut out)?,
        MeshFormat::Vdb => {
            return Err(invalid_input(
                "a .vdb file holds a level set, not a mesh: make it with \
                 splash_sph::level_set::LevelSet and write it with its write_file"
                    .into(),
            ));
        }
    }
    out.flush()
}

/// Writes a USD layer of `mesh` placed in time and space by `frame` (its values sampled at
/// the frame's time code, for a stage's value clips), whole or not at all, as
/// [`write_mesh_file`] does.
pub(crate) fn write_usd_file(
    path: &Path,
    mesh: &TriMesh,
    attributes: &VertexAttributes,
    frame: UsdFrame,
) -> Result<()> {
    atomic::write_file(path, |file| {
        check_mesh(mesh)?;
        check_attributes(mesh, attributes)?;
        let mut out = BufWriter::with_capacity(1 << 16, file);
        usd_write::write(mesh, attributes, frame, &mut out)?;
        out.flush()
    })
}

/// Writes `grids` over `tree` (see [`write_vdb`]) to `path`, whole or not at all, as
/// [`write_mesh_file`] does.
pub(crate) fn write_vdb_file(
    path: &Path,
    tree: &VdbTree,
    voxel_size: f32,
    grids: &[VdbGrid],
) -> Result<()> {
    atomic::write_file(path, |file| {
        let mut out = BufWriter::with_capacity(1 << 16, file);
        write_vdb(tree, voxel_size, grids, &mut out)?;
        out.flush()
    })
}

/// Writes to a temporary file in the same directory, fsyncs, renames onto `path`; on any error
/// removes the temporary and leaves an existing `path` untouched. Creates missing parent
/// directories.
pub fn write_mesh_file(path: &Path, mesh: &TriMesh, format: MeshFormat) -> Result<()> {
    write_mesh_file_with(path, mesh, &VertexAttributes::default(), format)
}

/// [`write_mesh_file`] with per-vertex attributes.
pub fn write_mesh_file_with(
    path: &Path,
    mesh: &TriMesh,
    attributes: &VertexAttributes,
    format: MeshFormat,
) -> Result<()> {
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
