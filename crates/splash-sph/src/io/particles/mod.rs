//! Reading particle frames: [`read_particles`] picks a reader by [`InputFormat`], each
//! `<format>_read.rs` reads one format into [`Particles`], and the other files hold what
//! several readers share: the layout a PLY header declares (`ply_layout`, which the PLY mesh
//! reader uses too), the attribute columns of PLY and text tables, the per-point arrays of VTK
//! and BGEO, and fixed-size binary records. The VTK readers also read a mesh's triangles for
//! [`read_mesh`](crate::io::read_mesh).

pub(super) mod attribute_columns;
mod bgeo_read;
mod csv_read;
mod ply_ascii_read;
mod ply_binary_read;
pub(super) mod ply_layout;
pub(super) mod ply_read;
pub(super) mod point_arrays;
mod raw_read;
mod records;
pub(super) mod vtk_read;
pub(super) mod vtu_read;
mod xyz_read;

use std::path::Path;

use crate::data::Particles;
use crate::error::Result;
// The readers' errors and helpers are io's (`super::failure` in every reader).
use super::failure;

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
pub fn read_particles(path: &Path, format: Option<InputFormat>) -> Result<Particles> {
    let format = match format {
        Some(format) => format,
        None => InputFormat::from_path(path)?,
    };
    match format {
        InputFormat::Ply => ply_read::read(path),
        InputFormat::Csv => csv_read::read(path),
        InputFormat::Raw => raw_read::read(path),
        InputFormat::Vtk => vtk_read::read(path),
        InputFormat::VtkXml => vtu_read::read(path),
        InputFormat::Bgeo => bgeo_read::read(path),
        InputFormat::Xyz => xyz_read::read(path),
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
    pub fn from_path(path: &Path) -> Result<Self> {
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
    pub fn parse(name: &str) -> Result<Self> {
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
