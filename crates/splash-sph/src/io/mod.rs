//! Reading particle frames and writing meshes.
//!
//! Particle inputs (see [`InputFormat`]), read in one pass with every per-particle attribute
//! the file has (see [`read_particles`]):
//! - PLY, ascii or binary (either byte order): the `vertex` element's `x`, `y`, `z` properties,
//!   of any scalar type and in any position; its other scalar properties are attributes, its
//!   list properties and the other elements are skipped.
//! - Text tables (`.csv`, `.txt`): see [`read_particles`] for the accepted dialect.
//! - Raw: little-endian `f32` `x y z` triples and nothing else.
//!
//! Every reader error names the file and what is wrong with it, with the line (text) or byte
//! offset (binary) where that helps. Coordinates must be finite. A frame without particles is
//! valid and reads as empty `Vec`s.
//!
//! Meshes are written as OBJ or PLY (binary little-endian or ascii), atomically when written to
//! a file with [`write_mesh_file`].

#[macro_use]
mod failure;

pub(crate) mod atomic;
mod attribute_columns;
mod csv;
mod lines;
mod obj;
mod ply;
mod ply_ascii;
mod ply_binary;
mod ply_layout;
mod ply_write;
mod pov;
mod raw;
mod records;

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::mesh::TriMesh;
use failure::{Failure, IoFailure, Result};

/// One particle frame: positions, and per-particle attributes by name.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Particles {
    /// One position per particle.
    pub positions: Vec<Vec3>,
    /// One value per particle each, by name (`velocity`, `density`, …).
    pub attributes: BTreeMap<String, Attribute>,
}

/// The values of one per-particle attribute.
#[derive(Debug, Clone, PartialEq)]
pub enum Attribute {
    /// One number per particle (`density`, `pressure`, …).
    Scalar(Vec<f32>),
    /// One vector per particle (`velocity`, `normal`, …).
    Vector(Vec<Vec3>),
}

impl Particles {
    /// Particles in the frame.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// Whether the frame has no particles.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }
}

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
}

const INPUT_EXTENSIONS: &str = ".ply, .csv, .txt, .bin, .raw";

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
            _ => bail_config!(
                "cannot tell the particle format of '{}' from its extension: known extensions are \
                 {INPUT_EXTENSIONS} (or give the input format explicitly: ply, csv or raw)",
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
            _ => bail_config!("unknown input format '{name}': expected ply, csv or raw"),
        }
    }
}

/// Opens a particle file, returning it with its length in bytes.
fn open_input(path: &Path) -> Result<(File, u64)> {
    let file = File::open(path).map_err(|e| Failure::io("cannot open the file", e))?;
    let metadata = file
        .metadata()
        .map_err(|e| Failure::io("cannot query the file's size", e))?;
    if metadata.is_dir() {
        // Reading it would fail with a less telling message, on some systems only later.
        let failure = IoFailure::of_kind(io::ErrorKind::IsADirectory, "it is a directory");
        return Err(failure.into());
    }
    Ok((file, metadata.len()))
}

/// File format of an output mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MeshFormat {
    /// Wavefront OBJ: `v`, `vn`, `f v//vn`.
    Obj,
    #[serde(rename = "ply")]
    /// Binary little-endian PLY.
    PlyBinary,
    /// Ascii PLY.
    PlyAscii,
    /// A POV-Ray include file declaring a `mesh2` object (see [`POV_OBJECT`]).
    Pov,
}

/// The name a `--format pov` file declares its mesh under: `object { SplashMesh … }`.
pub const POV_OBJECT: &str = "SplashMesh";

impl MeshFormat {
    /// File extension, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            Self::Obj => "obj",
            Self::PlyBinary | Self::PlyAscii => "ply",
            Self::Pov => "inc",
        }
    }

    /// Whether the format can carry per-vertex velocities (PLY `vx vy vz`).
    pub fn holds_velocities(self) -> bool {
        matches!(self, Self::PlyBinary | Self::PlyAscii)
    }

    /// Parses a format name as given on the command line: `obj`, `ply` (binary little-endian),
    /// `ply-ascii` or `pov` (POV-Ray `mesh2` include, `.inc`).
    pub fn parse(name: &str) -> crate::Result<Self> {
        match name.trim().to_ascii_lowercase().as_str() {
            "obj" => Ok(Self::Obj),
            "ply" => Ok(Self::PlyBinary),
            "ply-ascii" => Ok(Self::PlyAscii),
            "pov" | "inc" => Ok(Self::Pov),
            _ => bail_config!("unknown mesh format '{name}': expected obj, ply, ply-ascii or pov"),
        }
    }

    /// The format implied by the extension (`.obj`, `.ply` as binary, `.inc` as POV-Ray),
    /// case-insensitively.
    pub fn from_path(path: &Path) -> Option<Self> {
        let extension = path.extension()?.to_str()?.to_ascii_lowercase();
        match extension.as_str() {
            "obj" => Some(Self::Obj),
            "ply" => Some(Self::PlyBinary),
            "inc" => Some(Self::Pov),
            _ => None,
        }
    }
}

/// Per-vertex data written beside the mesh, where the format has room for it.
#[derive(Clone, Copy, Debug, Default)]
pub struct VertexAttributes<'a> {
    /// One velocity per vertex, written as the PLY vertex properties `vx vy vz` (float).
    pub velocities: Option<&'a [Vec3]>,
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
    if let Some(velocities) = attributes.velocities {
        if !format.holds_velocities() {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    ".{} files cannot hold vertex velocities",
                    format.extension()
                ),
            ));
        }
        if velocities.len() != mesh.vertices.len() {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "mesh has {} velocities for {} vertices",
                    velocities.len(),
                    mesh.vertices.len()
                ),
            ));
        }
    }
    let mut out = BufWriter::with_capacity(1 << 16, w);
    match format {
        MeshFormat::Obj => obj::write(mesh, &mut out)?,
        MeshFormat::PlyBinary => ply_write::write(mesh, attributes, false, &mut out)?,
        MeshFormat::PlyAscii => ply_write::write(mesh, attributes, true, &mut out)?,
        MeshFormat::Pov => pov::write(mesh, &mut out)?,
    }
    out.flush()
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

/// Turns a mesh on output so that a simulation's up axis becomes the one a tool expects.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum UpAxis {
    /// Z-up output from Y-up data: (x, y, z) → (x, −z, y), a quarter turn about +X.
    Z,
    /// Y-up output from Z-up data: (x, y, z) → (x, z, −y), the inverse turn.
    Y,
}

impl UpAxis {
    /// `y` or `z`.
    pub fn parse(name: &str) -> crate::Result<Self> {
        match name.trim().to_ascii_lowercase().as_str() {
            "z" => Ok(Self::Z),
            "y" => Ok(Self::Y),
            _ => bail_config!("unknown up axis '{name}': expected y or z"),
        }
    }

    /// Rotates points or directions in place (a rotation: lengths and winding are kept).
    pub fn rotate(self, vectors: &mut [Vec3]) {
        for v in vectors {
            *v = match self {
                Self::Z => Vec3::new(v.x, -v.z, v.y),
                Self::Y => Vec3::new(v.x, v.z, -v.y),
            };
        }
    }
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

/// Passes finite points through; `at` says where a non-finite one was found.
#[inline]
fn finite(p: Vec3, at: impl FnOnce() -> String) -> Result<Vec3> {
    if p.is_finite() {
        Ok(p)
    } else {
        Err(non_finite(p, &at()))
    }
}

#[cold]
fn non_finite(p: Vec3, at: &str) -> Failure {
    format_failure!(
        "{at} has a non-finite coordinate: ({}, {}, {})",
        p.x,
        p.y,
        p.z
    )
}

/// At most this many characters of a file's text are quoted in an error message, and at
/// most this many names listed: a file with no line breaks must not become a megabyte of text.
const QUOTED_CHARS: usize = 40;
const LISTED_NAMES: usize = 12;

/// `text` as an error message quotes it: cut to [`QUOTED_CHARS`] characters, with "…".
fn short(text: &str) -> String {
    match text.char_indices().nth(QUOTED_CHARS) {
        Some((end, _)) => format!("{}…", &text[..end]),
        None => text.to_string(),
    }
}

/// Names joined by commas for an error message: at most [`LISTED_NAMES`], each [`short`].
fn listed<'a>(names: impl IntoIterator<Item = &'a str>) -> String {
    let names: Vec<&str> = names.into_iter().collect();
    let mut out: Vec<String> = names.iter().take(LISTED_NAMES).map(|n| short(n)).collect();
    if names.len() > LISTED_NAMES {
        out.push(format!("… {} more", names.len() - LISTED_NAMES));
    }
    out.join(", ")
}
