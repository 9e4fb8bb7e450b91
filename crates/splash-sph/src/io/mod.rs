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
mod attribute_columns;
mod bgeo;
mod csv;
mod mesh_read;
mod obj;
mod obj_read;
mod ply;
mod ply_ascii;
mod ply_binary;
mod ply_layout;
mod ply_mesh;
mod ply_write;
mod point_arrays;
mod pov;
mod raw;
mod records;
mod text;
mod usd;
mod usd_stage;
mod vertex_attributes;
mod vtk_legacy;
mod vtk_write;
mod vtk_xml;
mod vtu_write;
mod xyz;

use std::io::{self, BufWriter, Write};
use std::path::Path;

use crate::data::TriMesh;
use failure::{invalid_input, listed, short};
pub use mesh_read::{MeshFile, read_mesh};

#[doc(no_inline)]
pub use crate::data::{Attribute, MeshFormat, Particles, UpAxis};
pub use pov::POV_OBJECT;
pub use usd::{USD_PRIM, UsdFrame};
pub use usd_stage::{
    USD_FRAMES_PER_SECOND, UsdClip, usd_stage_path, usd_topology_path, write_usd_stage,
};
pub use vertex_attributes::VertexAttributes;

/// Reads one particle frame, its positions and attributes; `format` overrides the guess from
/// the file's extension.
///
/// Attributes are the PLY `vertex` element's scalar properties other than `x`, `y`, `z` (list
/// properties are skipped), or the numeric columns of a text table with a header; raw files
/// have none. Values of any type are converted to `f32`, and are not checked for finiteness.
/// `{name}_x {name}_y {name}_z` make the vector attribute `{name}`, `vx vy vz` make
/// `velocity` and `nx ny nz` `normal`; any other property or column is a scalar attribute of
/// its own name (`density`). A triple whose name is also a property's or another triple's
/// stays three scalars.
///
/// Text tables: fields are separated by commas if the first data or header line has one, else
/// by semicolons if it has one, else by runs of spaces/tabs. Fields are trimmed and may be
/// wrapped in double quotes (a quoted field cannot contain the separator). Blank lines and lines
/// starting with `#` are skipped; CRLF line ends and a UTF-8 byte order mark are accepted. The
/// first line is a header if any of its fields is not a number; the header must then name
/// columns `x`, `y` and `z` (case-insensitive, anywhere), otherwise the first three columns are
/// used and the others ignored. A header's other columns are attributes if they hold a number
/// in the first row, and every later row must then hold one there; names compare ignoring
/// case, and of two columns of one name the first is read.
pub fn read_particles(path: &Path, format: Option<InputFormat>) -> crate::Result<Particles> {
    let format = match format {
        Some(format) => format,
        None => InputFormat::from_path(path)?,
    };
    match format {
        InputFormat::Ply => ply::read(path),
        InputFormat::Csv => csv::read(path),
        InputFormat::Raw => raw::read(path),
        InputFormat::Vtk => vtk_legacy::read(path),
        InputFormat::VtkXml => vtk_xml::read(path),
        InputFormat::Bgeo => bgeo::read(path),
        InputFormat::Xyz => xyz::read(path),
    }
    .map_err(|e| e.into_error(path))
}

/// File format of a particle frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InputFormat {
    /// PLY, ascii or binary.
    Ply,
    /// Text tables (`.csv`, `.txt`).
    Csv,
    /// Raw little-endian `f32` `x y z` triples (`.bin`, `.raw`).
    Raw,
    /// Legacy VTK, ascii or binary (`.vtk`).
    Vtk,
    /// VTK XML unstructured grid or poly data (`.vtu`, `.vtp`).
    VtkXml,
    /// Classic BGEO, version 5, plain or gzip-compressed (`.bgeo`, `.bgeo.gz`).
    Bgeo,
    /// `.xyz`: raw little-endian `f32` triples, or a text table when the file is text.
    Xyz,
}

const INPUT_EXTENSIONS: &str =
    ".ply, .csv, .txt, .bin, .raw, .vtk, .vtu, .vtp, .bgeo, .bgeo.gz, .xyz";

/// The input names `--input-format` accepts.
const INPUT_FORMATS: &str = "ply, csv, raw, vtk, vtu (or vtp), bgeo, xyz";

impl InputFormat {
    /// The format implied by the file's extension, case-insensitively: `.ply`; `.csv` and `.txt`
    /// (text tables, whatever their separator); `.bin` and `.raw` (raw `f32` triples).
    pub fn from_path(path: &Path) -> crate::Result<Self> {
        let extension = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match extension.as_deref() {
            Some("ply") => Ok(Self::Ply),
            Some("csv" | "txt") => Ok(Self::Csv),
            Some("bin" | "raw") => Ok(Self::Raw),
            Some("vtk") => Ok(Self::Vtk),
            Some("vtu" | "vtp") => Ok(Self::VtkXml),
            Some("bgeo") => Ok(Self::Bgeo),
            Some("xyz") => Ok(Self::Xyz),
            Some("gz" | "sc") if has_bgeo_stem(path) => Ok(Self::Bgeo),
            _ => bail_config!(
                "cannot tell the particle format of '{}' from its extension: known extensions are \
                 {INPUT_EXTENSIONS} (or give the input format explicitly: {INPUT_FORMATS})",
                path.display()
            ),
        }
    }

    /// Parses a format name as given on the command line: `ply`, `csv` or `raw`.
    pub fn parse(name: &str) -> crate::Result<Self> {
        match name.trim().to_ascii_lowercase().as_str() {
            "ply" => Ok(Self::Ply),
            "csv" => Ok(Self::Csv),
            "raw" => Ok(Self::Raw),
            "vtk" => Ok(Self::Vtk),
            "vtu" | "vtp" | "vtk-xml" => Ok(Self::VtkXml),
            "bgeo" => Ok(Self::Bgeo),
            "xyz" => Ok(Self::Xyz),
            _ => bail_config!("unknown input format '{name}': expected {INPUT_FORMATS}"),
        }
    }
}

/// Whether `path` is `….bgeo.gz` or `….bgeo.sc` (any case).
fn has_bgeo_stem(path: &Path) -> bool {
    path.file_stem()
        .and_then(|s| Path::new(s).extension())
        .is_some_and(|e| e.eq_ignore_ascii_case("bgeo"))
}

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
