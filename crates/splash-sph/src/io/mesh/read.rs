//! Reading back the meshes splash writes (OBJ, PLY, VTK), with their normals and vertex
//! attributes, for tools that load a farm's output: the Python package, the Blender add-on.
//! The whole file is read first; its size bounds every allocation after it.

use std::collections::BTreeMap;
use std::path::Path;

use super::failure::Result;
use super::{obj_read, ply_read};
use crate::data::{Attribute, MeshFormat, Particles, TriMesh};
use crate::io::particles::{point_arrays, vtk_read, vtu_read};

/// A mesh read from a file: its triangles, vertex normals (empty when the file has none) and
/// per-vertex attributes by name.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MeshFile {
    /// Vertices, normals and triangles.
    pub mesh: TriMesh,
    /// One value per vertex each: PLY `vx vy vz` as `velocity`, `{name}_x {name}_y {name}_z`
    /// as the vector `{name}`, other properties as scalars; VTK point data by its name.
    pub attributes: BTreeMap<String, Attribute>,
}

/// Reads a mesh that [`write_mesh_file`](super::write_mesh_file) wrote, by its extension:
/// `.obj`, `.ply` (binary either byte order, or ascii), legacy `.vtk` (`POLYDATA`, binary or
/// ascii), `.vtu` or `.vtp` (any data mode, compressed or not). POV-Ray includes are not read.
///
/// Faces must be triangles; PLY `nx ny nz` and VTK's `Normals` array are the normals, one per
/// vertex; a triangle's corners must be vertices of the file, and vertices finite. Errors name
/// the file and what is wrong: [`Error::MeshFormat`](crate::Error::MeshFormat) for the
/// content, [`Error::Io`](crate::Error::Io) when it cannot be read.
pub fn read_mesh(path: &Path) -> crate::error::Result<MeshFile> {
    read(path).map_err(|e| e.into_mesh_error(path))
}

fn read(path: &Path) -> Result<MeshFile> {
    let format = MeshFormat::from_path(path);
    let parse: fn(&[u8]) -> Result<MeshFile> = match format {
        Some(MeshFormat::Obj) => |data| {
            Ok(MeshFile {
                mesh: obj_read::parse(data)?,
                attributes: BTreeMap::new(),
            })
        },
        Some(MeshFormat::PlyBinary | MeshFormat::PlyAscii) => |data| {
            let (mesh, attributes) = ply_read::parse(data)?;
            Ok(with_normals(mesh, attributes, "normal"))
        },
        Some(MeshFormat::Vtu | MeshFormat::Vtp) => |data| Ok(vtk_mesh(vtu_read::parse_mesh(data)?)),
        Some(MeshFormat::Vtk) => |data| Ok(vtk_mesh(vtk_read::parse_mesh(data)?)),
        Some(MeshFormat::Pov | MeshFormat::Usd | MeshFormat::Vdb) | None => bail_format!(
            "cannot tell the mesh format from the extension: meshes are read from .obj, .ply, \
             .vtk, .vtu and .vtp files"
        ),
    };
    let file = parse(&point_arrays::read_all(path)?)?;
    check(&file)?;
    Ok(file)
}

/// A VTK file's points and triangles as a mesh, its point data `Normals` the normals.
fn vtk_mesh((points, triangles): (Particles, Vec<[u32; 3]>)) -> MeshFile {
    let mesh = TriMesh {
        vertices: points.positions,
        normals: Vec::new(),
        triangles,
    };
    with_normals(mesh, points.attributes, "Normals")
}

/// Moves the vector attribute `name` into the mesh's normals.
fn with_normals(
    mut mesh: TriMesh,
    mut attributes: BTreeMap<String, Attribute>,
    name: &str,
) -> MeshFile {
    match attributes.remove(name) {
        Some(Attribute::Vector(normals)) => mesh.normals = normals,
        Some(other) => drop(attributes.insert(name.to_owned(), other)),
        None => {}
    }
    MeshFile { mesh, attributes }
}

/// What every format must hold: corners that are vertices, one normal per vertex if any.
fn check(file: &MeshFile) -> Result<()> {
    let mesh = &file.mesh;
    let n = mesh.vertices.len();
    let beyond = mesh.triangles.iter().enumerate().find_map(|(t, corners)| {
        let bad = corners.iter().find(|&&i| i as usize >= n)?;
        Some((t, *bad))
    });
    if let Some((t, index)) = beyond {
        bail_format!("triangle {t} refers to vertex {index} of {n}");
    }
    if !mesh.normals.is_empty() && mesh.normals.len() != n {
        bail_format!("{} normals for {n} vertices", mesh.normals.len());
    }
    if let Some(v) = mesh.vertices.iter().position(|v| !v.is_finite()) {
        bail_format!("vertex {v} has a non-finite coordinate");
    }
    let wrong_length = file.attributes.iter().find(|(_, a)| match a {
        Attribute::Scalar(s) => s.len() != n,
        Attribute::Vector(v) => v.len() != n,
    });
    if let Some((name, _)) = wrong_length {
        bail_format!(
            "the attribute '{}' has not one value per vertex",
            super::short(name)
        );
    }
    Ok(())
}
