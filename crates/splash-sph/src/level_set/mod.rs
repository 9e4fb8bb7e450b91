//! A mesh's narrow-band level set, for OpenVDB output (`--format vdb`): the signed distance to
//! the mesh (negative inside) at voxel centres `ijk · voxel`, active within a band of
//! [`HALF_WIDTH_VOXELS`] voxels on either side, stored as OpenVDB stores it (a tree):
//! 8³ leaves only where the band is, so that memory follows the surface, not the volume.
//!
//! The distances are the mesh's own, exact: each triangle offers the nearest point of itself
//! (Ericson) to the voxels of its face's prism and of the wedges and cones of the edges and
//! corners it owns, and each voxel keeps the least (`scan.rs`, Mauch's characteristic
//! polyhedra). They are signed by the nearest triangle's normal where the normals around it are
//! close enough for that to be right (`cones.rs`), else by the angle-weighted pseudonormals of
//! the triangles around it (as [`SignedDistance`](crate::mesh::SignedDistance) signs them). A
//! leaf's voxels beyond the band take the sign of their neighbours, which the surface cannot
//! pass between; inactive tiles carry ±background by the sign of the region they lie in (see
//! `tiles.rs`).

mod cones;
mod scan;
mod tiles;

use glam::{IVec3, Vec3};
use rayon::prelude::*;

use std::path::Path;

use crate::data::{Attribute, TriMesh};
use crate::error::Result;
use crate::io::{self, VdbGrid, VdbLeaf, VdbTree, VdbValues};
use crate::mesh::signed_distance::signed_distance_among;
use crate::mesh::unit_normal;
use cones::Cones;
use scan::Work;

/// The level set's grid in a `.vdb` file.
pub const SURFACE_GRID: &str = "surface";

/// The narrow band's half width in voxels (OpenVDB's `LEVEL_SET_HALF_WIDTH`).
pub const HALF_WIDTH_VOXELS: f32 = 3.0;

/// The six face neighbours of a voxel.
const STEPS: [IVec3; 6] = [
    IVec3::X,
    IVec3::NEG_X,
    IVec3::Y,
    IVec3::NEG_Y,
    IVec3::Z,
    IVec3::NEG_Z,
];

/// The triangles around each vertex (compressed rows).
struct Fans {
    start: Vec<u32>,
    triangles: Vec<u32>,
}

impl Fans {
    fn new(mesh: &TriMesh) -> Fans {
        let mut start = vec![0u32; mesh.vertices.len() + 1];
        for t in &mesh.triangles {
            t.iter().for_each(|&v| start[v as usize + 1] += 1);
        }
        for v in 0..mesh.vertices.len() {
            start[v + 1] += start[v];
        }
        let mut next = start.clone();
        let mut triangles = vec![0u32; 3 * mesh.triangles.len()];
        for (i, t) in mesh.triangles.iter().enumerate() {
            for &v in t {
                triangles[next[v as usize] as usize] = i as u32;
                next[v as usize] += 1;
            }
        }
        Fans { start, triangles }
    }

    fn around(&self, v: u32) -> &[u32] {
        &self.triangles[self.start[v as usize] as usize..self.start[v as usize + 1] as usize]
    }
}

/// A mesh's narrow-band signed distance on a voxel grid.
#[derive(Debug, Clone)]
pub struct LevelSet {
    /// The voxels' edge, in world units; voxel `ijk` is centred at `ijk · voxel`.
    pub voxel: f32,
    /// The band's half width in world units: the background of inactive voxels.
    pub half_width: f32,
    /// The active voxels, as OpenVDB's tree holds them.
    pub(crate) tree: VdbTree,
    /// The signed distance of each active voxel, in the tree's order.
    pub values: Vec<f32>,
}

impl LevelSet {
    /// The level set of `mesh` (closed, wound counter-clockwise from outside) on voxels of
    /// edge `voxel`. Errors for a voxel that is not a positive number, a triangle naming a
    /// missing vertex, and a vertex that is not finite.
    pub fn of_mesh(mesh: &TriMesh, voxel: f32) -> Result<LevelSet> {
        if !(voxel.is_finite() && voxel > 0.0) {
            bail_config!("a level set's voxel size must be a positive number, not {voxel}");
        }
        let n = mesh.vertices.len();
        if let Some(t) = mesh
            .triangles
            .iter()
            .position(|t| t.iter().any(|&i| i as usize >= n))
        {
            bail_input!("mesh triangle {t} names a vertex beyond its {n} vertices");
        }
        if let Some(v) = mesh.vertices.iter().position(|v| !v.is_finite()) {
            bail_input!("mesh vertex {v} is not finite: {}", mesh.vertices[v]);
        }
        let half_width = HALF_WIDTH_VOXELS * voxel;
        let cones = Cones::new(mesh);
        let fans = Fans::new(mesh);
        let band = scan::band(mesh, &cones, &fans, voxel, half_width);
        let signs = Signs {
            mesh,
            cones: &cones,
            fans: &fans,
        };
        // In the file's order, as the band's leaves are.
        let (leaves, values): (Vec<VdbLeaf>, Vec<Vec<f32>>) = band
            .origins
            .par_iter()
            .zip(band.leaves)
            .filter_map(|(&origin, work)| leaf(origin, &*work.into_inner()?, &signs, voxel))
            .unzip();
        let mut tree = VdbTree::new(leaves);
        tiles::fill_signs(&mut tree);
        let values = values.concat();
        Ok(LevelSet {
            voxel,
            half_width,
            tree,
            values,
        })
    }

    /// The grid a per-voxel attribute is written as: `v` for `velocity` (the name Blender's
    /// and Houdini's motion blur read), else the attribute's own name.
    pub fn grid_name(attribute: &str) -> &str {
        if attribute == "velocity" {
            "v"
        } else {
            attribute
        }
    }

    /// Writes the level set as the float grid `surface` (class `level set`) and each of
    /// `attributes` (one value per active voxel, in the tree's order) as a grid named by
    /// [`grid_name`](Self::grid_name), to `path`, whole or not at all.
    pub fn write_file(&self, path: &Path, attributes: &[(String, Attribute)]) -> Result<()> {
        let mut grids = vec![VdbGrid {
            name: SURFACE_GRID,
            values: VdbValues::LevelSet {
                values: &self.values,
                half_width: self.half_width,
            },
        }];
        for (name, values) in attributes {
            grids.push(VdbGrid {
                name: Self::grid_name(name),
                values: match values {
                    Attribute::Scalar(s) => VdbValues::Scalar(s),
                    Attribute::Vector(v) => VdbValues::Vector(v),
                },
            });
        }
        io::write_vdb_file(path, &self.tree, self.voxel, &grids)
    }

    /// The centres of the active voxels, in the tree's order.
    pub fn positions(&self) -> Vec<Vec3> {
        self.tree
            .leaves
            .iter()
            .flat_map(|l| ones(&l.active).map(move |n| position(l.origin, n, self.voxel)))
            .collect()
    }

    /// The index coordinates of the active voxels, in the tree's order.
    pub fn coordinates(&self) -> Vec<[i32; 3]> {
        self.tree
            .leaves
            .iter()
            .flat_map(|l| ones(&l.active).map(move |n| (IVec3::from(l.origin) + offset(n)).into()))
            .collect()
    }
}

/// What signs a voxel's distance from its nearest triangle.
struct Signs<'a> {
    mesh: &'a TriMesh,
    cones: &'a Cones,
    fans: &'a Fans,
}

impl Signs<'_> {
    /// The distance `d` from `p` to the mesh, nearest to triangle `t`, signed: by `t`'s normal
    /// where the cones are narrow at `t` (`cones.rs`: a point nearest to `t` then lies within
    /// 90° of its normal on its own side), else by the pseudonormals of the triangles around `t`.
    fn signed(&self, p: Vec3, d: f32, t: u32) -> f32 {
        let (vertices, triangles) = (&self.mesh.vertices, &self.mesh.triangles);
        let tri = triangles[t as usize];
        let n = unit_normal(&tri, vertices);
        if n != Vec3::ZERO && self.cones.narrow(tri, n) {
            // The nearest point lies in the face's plane, so its offset along the normal is
            // that of any corner.
            let inside = (p - vertices[tri[0] as usize]).dot(n) < 0.0;
            return if inside { -d } else { d };
        }
        let around = tri.into_iter().flat_map(|v| self.fans.around(v));
        signed_distance_among(p, around.copied(), vertices, triangles)
            .expect("a triangle around its own corners")
    }
}

/// The leaf at `origin` from its voxels' distances and nearest triangles: active within the
/// band, the others signed by their neighbours within the leaf; None when no voxel is active.
fn leaf(origin: [i32; 3], work: &Work, signs: &Signs, voxel: f32) -> Option<(VdbLeaf, Vec<f32>)> {
    let mut active = [0u64; 8];
    let mut values = Vec::new();
    // Signs: 1 outside, -1 inside, 0 unknown.
    let mut sign = [0i8; 512];
    for n in 0..512 {
        if let Some((d, t)) = work.get(n) {
            let d = signs.signed(position(origin, n, voxel), d, t);
            sign[n] = if d < 0.0 { -1 } else { 1 };
            active[n >> 6] |= 1 << (n & 63);
            values.push(d);
        }
    }
    if values.is_empty() {
        return None;
    }
    // Unknown voxels lie beyond the band, three voxels or more from the surface, which so
    // passes between no unknown voxel and its neighbours: a flood from the known ones within
    // the leaf signs them all (the leaf is connected, so every unknown region borders a known
    // voxel).
    let mut queue: Vec<usize> = (0..512).filter(|&n| sign[n] != 0).collect();
    while let Some(n) = queue.pop() {
        let v = offset(n);
        for step in STEPS {
            let u = v + step;
            if u.min_element() < 0 || u.max_element() > 7 {
                continue;
            }
            let m = voxel_bit(u);
            if sign[m] == 0 {
                sign[m] = sign[n];
                queue.push(m);
            }
        }
    }
    let mut outside = [0u64; 8];
    for (n, &s) in sign.iter().enumerate() {
        if s > 0 {
            outside[n >> 6] |= 1 << (n & 63);
        }
    }
    Some((
        VdbLeaf {
            origin,
            active,
            outside,
        },
        values,
    ))
}

/// Bit `n` of a leaf's mask is voxel `(n >> 6, (n >> 3) & 7, n & 7)` from its origin.
fn offset(n: usize) -> IVec3 {
    let n = n as i32;
    IVec3::new(n >> 6, (n >> 3) & 7, n & 7)
}

/// The bit of voxel `v` in its leaf's masks.
fn voxel_bit(v: IVec3) -> usize {
    let l = v & 7;
    ((l.x << 6) | (l.y << 3) | l.z) as usize
}

/// The centre of voxel `n` of the leaf at `origin`.
fn position(origin: [i32; 3], n: usize, voxel: f32) -> Vec3 {
    (IVec3::from(origin) + offset(n)).as_vec3() * voxel
}

/// The set bits of a mask.
pub(crate) fn ones(mask: &[u64]) -> impl Iterator<Item = usize> + '_ {
    mask.iter().enumerate().flat_map(|(w, &word)| {
        let mut bits = word;
        std::iter::from_fn(move || {
            (bits != 0).then(|| {
                let b = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                (w << 6) | b
            })
        })
    })
}

#[cfg(test)]
mod tests;
