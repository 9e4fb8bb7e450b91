//! The data every part of splash passes on, on the crate's ground floor: one particle frame as
//! every reader returns it (positions, and per-particle attributes by name), the triangle mesh
//! every engine makes, and how a mesh is written out (its file format and up axis). The
//! readers, the engines, post-processing, the writers and the configuration all build on these
//! types; this module builds on nothing of the crate but its errors.

use std::collections::BTreeMap;
use std::path::Path;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::error::Result;

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

    /// Drops the particles outside the box `[min x, min y, min z, max x, max y, max z]`
    /// (bounds included; a non-finite position is outside), and their attribute values;
    /// returns how many were dropped.
    pub fn retain_in_box(&mut self, aabb: [f32; 6]) -> usize {
        let (lo, hi) = (Vec3::from_slice(&aabb[..3]), Vec3::from_slice(&aabb[3..]));
        let keep: Vec<bool> = self
            .positions
            .iter()
            .map(|p| p.cmpge(lo).all() && p.cmple(hi).all())
            .collect();
        let dropped = keep.iter().filter(|&&k| !k).count();
        if dropped == 0 {
            return 0;
        }
        fn retain<T>(values: &mut Vec<T>, keep: &[bool]) {
            let mut k = keep.iter();
            values.retain(|_| *k.next().unwrap_or(&false));
        }
        retain(&mut self.positions, &keep);
        for a in self.attributes.values_mut() {
            match a {
                Attribute::Scalar(s) => retain(s, &keep),
                Attribute::Vector(v) => retain(v, &keep),
            }
        }
        dropped
    }
}

/// An indexed triangle mesh with one normal per vertex; triangles wind counter-clockwise seen
/// from outside the fluid.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TriMesh {
    /// Vertex positions.
    pub vertices: Vec<Vec3>,
    /// One unit normal per vertex, pointing out of the fluid; empty when none were asked for.
    pub normals: Vec<Vec3>,
    /// Indices into `vertices`, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
}

impl TriMesh {
    /// Whether the mesh has no triangles.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// Bytes held by the mesh's arrays.
    pub fn heap_bytes(&self) -> usize {
        self.vertices.capacity() * size_of::<Vec3>()
            + self.normals.capacity() * size_of::<Vec3>()
            + self.triangles.capacity() * size_of::<[u32; 3]>()
    }
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
    /// A POV-Ray include file declaring a `mesh2` object (see
    /// [`POV_OBJECT`](crate::io::POV_OBJECT)).
    Pov,
    /// VTK legacy binary `POLYDATA` (`.vtk`).
    Vtk,
    /// VTK XML unstructured grid (`.vtu`), binary and zlib-compressed.
    Vtu,
    /// VTK XML poly data (`.vtp`), binary and zlib-compressed.
    Vtp,
    /// A USD text layer (`.usda`) holding one `UsdGeomMesh`.
    Usd,
    /// An OpenVDB file (`.vdb`): the mesh's narrow-band level set, a float grid `surface`
    /// (see [`LevelSet`](crate::level_set::LevelSet)), and a grid per attribute.
    Vdb,
}

impl MeshFormat {
    /// File extension, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            Self::Obj => "obj",
            Self::PlyBinary | Self::PlyAscii => "ply",
            Self::Pov => "inc",
            Self::Vtk => "vtk",
            Self::Vtu => "vtu",
            Self::Vtp => "vtp",
            Self::Usd => "usda",
            Self::Vdb => "vdb",
        }
    }

    /// Whether the format can carry per-vertex attributes (PLY properties, VTK point data, USD
    /// primvars), or for VDB per-voxel ones (a grid each).
    pub fn holds_attributes(self) -> bool {
        !matches!(self, Self::Obj | Self::Pov)
    }

    /// Whether the format can carry per-vertex velocities: see
    /// [`holds_attributes`](Self::holds_attributes).
    pub fn holds_velocities(self) -> bool {
        self.holds_attributes()
    }

    /// Parses a format name as given on the command line: `obj`, `ply` (binary little-endian),
    /// `ply-ascii`, `pov` (POV-Ray `mesh2` include, `.inc`), `vtk` (legacy binary), `vtu` or
    /// `vtp` (XML, compressed), `usd` (USD text layer, `.usda`), `vdb` (OpenVDB level set).
    pub fn parse(name: &str) -> Result<Self> {
        match name.trim().to_ascii_lowercase().as_str() {
            "obj" => Ok(Self::Obj),
            "ply" => Ok(Self::PlyBinary),
            "ply-ascii" => Ok(Self::PlyAscii),
            "pov" | "inc" => Ok(Self::Pov),
            "vtk" => Ok(Self::Vtk),
            "vtu" => Ok(Self::Vtu),
            "vtp" => Ok(Self::Vtp),
            "usd" | "usda" => Ok(Self::Usd),
            "vdb" => Ok(Self::Vdb),
            _ => bail_config!(
                "unknown mesh format '{name}': expected obj, ply, ply-ascii, pov, vtk, vtu, vtp, \
                 usd or vdb"
            ),
        }
    }

    /// The format implied by the extension (`.obj`, `.ply` as binary, `.inc` as POV-Ray,
    /// `.vtk`, `.vtu`, `.vtp`, `.usda` and `.usd` as USD text, `.vdb`), case-insensitively.
    pub fn from_path(path: &Path) -> Option<Self> {
        let extension = path.extension()?.to_str()?.to_ascii_lowercase();
        match extension.as_str() {
            "obj" => Some(Self::Obj),
            "ply" => Some(Self::PlyBinary),
            "inc" => Some(Self::Pov),
            "vtk" => Some(Self::Vtk),
            "vtu" => Some(Self::Vtu),
            "vtp" => Some(Self::Vtp),
            "usda" | "usd" => Some(Self::Usd),
            "vdb" => Some(Self::Vdb),
            _ => None,
        }
    }
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
    pub fn parse(name: &str) -> Result<Self> {
        match name.trim().to_ascii_lowercase().as_str() {
            "z" => Ok(Self::Z),
            "y" => Ok(Self::Y),
            _ => bail_config!("unknown up axis '{name}': expected y or z"),
        }
    }

    /// The turn that undoes this one.
    pub fn inverse(self) -> Self {
        match self {
            Self::Z => Self::Y,
            Self::Y => Self::Z,
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

    /// Rotates a mesh's vertices and normals and the vector attributes of its vertices.
    pub fn rotate_mesh(self, mesh: &mut TriMesh, attributes: &mut [(String, Attribute)]) {
        self.rotate(&mut mesh.vertices);
        self.rotate(&mut mesh.normals);
        for (_, a) in attributes {
            if let Attribute::Vector(v) = a {
                self.rotate(v);
            }
        }
    }
}
