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
//! binary, VTK XML (`.vtu`, `.vtp`) or USD text layers (`.usda`), and as OpenVDB level sets
//! (`.vdb`, [`LevelSet::write_file`](crate::level_set::LevelSet::write_file)), atomically when written to a
//! file with [`write_mesh_file`]. PLY, VTK and USD files can carry per-vertex attributes
//! ([`VertexAttributes`]). [`read_mesh`] reads them back, but for POV-Ray's and USD's. A
//! sequence of USD layers plays as one animated mesh through a stage of value clips, which a
//! [`Batch`](crate::pipeline::Batch) writes after its frames.

// The layout, for whoever adds a format. io/ is split by what flows through it, and a file that
// reads or writes one format is named `<format>_read.rs` or `<format>_write.rs`, in the folder
// of what it reads or writes:
// - particles/: particle frames in. mod.rs holds `read_particles` and `InputFormat`; ply_read.rs
//   (the header, with ply_ascii_read.rs and ply_binary_read.rs for the payload), csv_read.rs,
//   raw_read.rs, xyz_read.rs, bgeo_read.rs, vtk_read.rs (legacy VTK) and vtu_read.rs (VTK XML,
//   `.vtu` and `.vtp`).
// - mesh/: meshes out, and back in. mod.rs holds `write_mesh` and its kin, read.rs `read_mesh`;
//   obj_write.rs, ply_write.rs, pov_write.rs, vtk_write.rs, vtu_write.rs (`.vtu` and `.vtp`),
//   usd_write.rs (one layer), usd_stage_write.rs (a sequence's stage), vdb_write.rs (OpenVDB
//   grids: the level set that level_set/ computes, and attribute grids); obj_read.rs, ply_read.rs.
//   VTK meshes are read by particles/vtk_read.rs and vtu_read.rs, which read triangles too.
// - text/: text in and out. lines.rs reads the lines of text inputs; float_text.rs (with
//   decimal_lanes.rs, its AVX-512 path) and text_records.rs format the numbers of text outputs.
// - here: failure.rs, every reader's and writer's errors before the file's path is added, and
//   atomic.rs, files replaced whole or not at all (meshes, and preview PNGs).
// A file without a direction in its name holds what several readers or writers of its folder
// share (ply_layout.rs, attribute_columns.rs, point_arrays.rs, records.rs, vertex_attributes.rs).
// The types read and written (`Particles`, `Attribute`, `TriMesh`, `MeshFormat`, `UpAxis`) are
// the crate's own, on its ground floor (data.rs), and re-exported here. Between the folders,
// text/ imports neither other, particles/ imports text/, and mesh/ imports both.

#[macro_use]
mod failure;

pub(crate) mod atomic;
mod mesh;
mod particles;
mod text;

#[doc(no_inline)]
pub use crate::data::{Attribute, MeshFormat, Particles, UpAxis};
pub use mesh::{
    MeshFile, POV_OBJECT, USD_PRIM, VertexAttributes, read_mesh, write_mesh, write_mesh_file,
    write_mesh_file_with, write_mesh_with,
};
pub(crate) use mesh::{
    USD_FRAMES_PER_SECOND, UsdClip, UsdFrame, VdbGrid, VdbLeaf, VdbNode, VdbTree, VdbValues,
    usd_stage_path, usd_topology_path, vdb_file_order, vdb_node_origin, vdb_slot, write_usd_file,
    write_usd_stage, write_vdb_file,
};
pub use particles::{InputFormat, read_particles};
