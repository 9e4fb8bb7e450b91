//! A mesh's narrow-band level set, for OpenVDB output (`--format vdb`): the signed distance to
//! the mesh (negative inside) at voxel centres `ijk · voxel`, active within a band of
//! [`HALF_WIDTH_VOXELS`] voxels on either side, stored as OpenVDB stores it ([`VdbTree`]):
//! 8³ leaves only where the band is, so that memory follows the surface, not the volume.
//!
//! The distances are the mesh's own: the nearest point of the nearest triangle (Ericson), signed
//! by angle-weighted pseudonormals (as [`SignedDistance`](crate::mesh::SignedDistance) signs
//! them). Each triangle offers its distance to the voxels within about a voxel of it, which
//! keep the least, and are signed by the triangles around their nearest one. Farther out, as in
//! OpenVDB's `meshToVolume`, each voxel starts from the triangles nearest to its six neighbours,
//! layer after layer, steps to nearer ones across edges and corners, and takes its sign from
//! them: a voxel more than a voxel from the surface has the sign of its neighbours, as the
//! surface cannot pass between them. Inactive voxels and tiles carry ±background by the sign of
//! the region they lie in (see `tiles.rs`).

mod tiles;

use glam::{IVec3, Vec3};
use rayon::prelude::*;
use rustc_hash::{FxHashMap, FxHashSet};

use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

use crate::data::{Attribute, TriMesh};
use crate::error::Result;
use crate::io::{self, VdbGrid, VdbLeaf, VdbTree, VdbValues};
use crate::mesh::signed_distance::{signed_distance_among, triangle_distance};

/// The level set's grid in a `.vdb` file.
pub const SURFACE_GRID: &str = "surface";

/// The narrow band's half width in voxels (OpenVDB's `LEVEL_SET_HALF_WIDTH`).
pub const HALF_WIDTH_VOXELS: f32 = 3.0;

/// Seeds are queried within this many voxels of a triangle: more than one, so that a voxel
/// left to its neighbours lies more than a voxel from the surface and shares their sign.
const SEED_VOXELS: f32 = 1.05;

/// Layers of neighbours after the seeds: enough to cross the band's remaining
/// `HALF_WIDTH_VOXELS − SEED_VOXELS` voxels along the axes' staircase (√3 times longer).
const LAYERS: usize = 4;

/// Steps at most from a neighbour's nearest triangle to a nearer one around its corners: the
/// nearest triangle moves along the surface from voxel to voxel, a triangle or two per voxel.
const DESCENT: usize = 8;
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
    /// The active voxels.
    pub tree: VdbTree,
    /// The signed distance of each active voxel, in the tree's order.
    pub values: Vec<f32>,
}

/// A leaf being computed: each voxel's distance and nearest triangle, packed as the distance's
/// bits over the triangle's index (so that, while distances are unsigned, the least is the
/// nearest); `u64::MAX` until known.
struct Work([AtomicU64; 512]);

impl Work {
    fn new() -> Work {
        Work([const { AtomicU64::new(u64::MAX) }; 512])
    }

    fn get(&self, n: usize) -> Option<(f32, u32)> {
        let packed = self.0[n].load(Ordering::Relaxed);
        (packed != u64::MAX).then(|| (f32::from_bits((packed >> 32) as u32), packed as u32))
    }

    fn set(&self, n: usize, d: f32, t: u32) {
        self.0[n].store(pack(d, t), Ordering::Relaxed);
    }

    /// Keeps the nearer of what voxel `n` has and `d` (unsigned) to triangle `t`.
    fn offer(&self, n: usize, d: f32, t: u32) {
        self.0[n].fetch_min(pack(d, t), Ordering::Relaxed);
    }

    /// Each voxel's signed distance, NaN where unknown.
    fn distances(&self) -> [f32; 512] {
        std::array::from_fn(|n| self.get(n).map_or(f32::NAN, |(d, _)| d))
    }
}

fn pack(d: f32, t: u32) -> u64 {
    (u64::from(d.to_bits()) << 32) | u64::from(t)
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
        let (origins, work) = seeds(mesh, voxel, half_width);
        let index: FxHashMap<[i32; 3], usize> =
            origins.iter().enumerate().map(|(i, &o)| (o, i)).collect();
        let fans = Fans::new(mesh);
        let near = Near { mesh, fans: &fans };
        // The seeds' signs, from the pseudonormals of the triangles around their nearest one.
        origins.par_iter().zip(&work).for_each(|(&origin, w)| {
            for n in 0..512 {
                if let Some((_, t)) = w.get(n) {
                    let p = position(origin, n, voxel);
                    let around = mesh.triangles[t as usize]
                        .into_iter()
                        .flat_map(|v| fans.around(v));
                    let d =
                        signed_distance_among(p, around.copied(), &mesh.vertices, &mesh.triangles)
                            .expect("a triangle around its own corners");
                    w.set(n, d, t);
                }
            }
        });
        for _ in 0..LAYERS {
            let found: Vec<Vec<(usize, f32, u32)>> = origins
                .par_iter()
                .enumerate()
                .map(|(i, &origin)| grow(i, origin, &index, &work, &near, voxel))
                .collect();
            if found.iter().all(Vec::is_empty) {
                break;
            }
            for (w, found) in work.iter().zip(found) {
                for (n, d, t) in found {
                    w.set(n, d, t);
                }
            }
        }
        let leaves: Vec<(VdbLeaf, Vec<f32>)> = origins
            .par_iter()
            .zip(work)
            .filter_map(|(&origin, w)| leaf(origin, &w.distances(), half_width))
            .collect();
        let mut values_of: FxHashMap<[i32; 3], Vec<f32>> = FxHashMap::default();
        let mut plain = Vec::with_capacity(leaves.len());
        for (l, v) in leaves {
            values_of.insert(l.origin, v);
            plain.push(l);
        }
        let mut tree = VdbTree::new(plain);
        tiles::fill_signs(&mut tree);
        let values = tree
            .leaves
            .iter()
            .flat_map(|l| values_of.remove(&l.origin).unwrap_or_default())
            .collect();
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

/// The leaves within the band of some triangle (every triangle's box grown by `half_width`),
/// sorted, with the unsigned distance to the nearest triangle and that triangle at every voxel
/// within [`SEED_VOXELS`] of one: each triangle offers its distance to the voxels of its box
/// grown by that much, and each voxel keeps the least.
fn seeds(mesh: &TriMesh, voxel: f32, half_width: f32) -> (Vec<[i32; 3]>, Vec<Work>) {
    let boxes = |grow: f32| {
        mesh.triangles
            .par_iter()
            .enumerate()
            .filter_map(move |(i, t)| {
                let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
                let lo = ((a.min(b).min(c) - grow) / voxel).ceil();
                let hi = ((a.max(b).max(c) + grow) / voxel).floor();
                // Voxel indices are i32 (OpenVDB's Coord); farther triangles have no voxels.
                let fits = |v: Vec3| v.abs().max_element() < (i32::MAX - 16) as f32;
                (fits(lo) && fits(hi)).then(|| (i as u32, lo.as_ivec3(), hi.as_ivec3()))
            })
    };
    let leaves: FxHashSet<[i32; 3]> = boxes(half_width)
        .fold(
            FxHashSet::default,
            |mut set, (_, lo, hi): (u32, IVec3, IVec3)| {
                set.extend(cells_between(lo >> 3i32, hi >> 3i32).map(|l| (l << 3i32).to_array()));
                set
            },
        )
        .reduce(FxHashSet::default, |a, b| {
            let (small, mut large) = if a.len() < b.len() { (a, b) } else { (b, a) };
            large.extend(small);
            large
        });
    let mut origins: Vec<[i32; 3]> = leaves.into_iter().collect();
    origins.par_sort_unstable();
    let index: FxHashMap<[i32; 3], usize> =
        origins.iter().enumerate().map(|(i, &o)| (o, i)).collect();
    let work: Vec<Work> = (0..origins.len()).map(|_| Work::new()).collect();
    let reach = SEED_VOXELS * voxel;
    boxes(reach).for_each(|(t, lo, hi): (u32, IVec3, IVec3)| {
        let tri = mesh.triangles[t as usize];
        let [a, b, c] = tri.map(|i| mesh.vertices[i as usize]);
        // Only voxels near the triangle's plane can be near the triangle.
        let normal = (b - a).cross(c - a).normalize_or_zero();
        // Leaf by leaf (a box meets one or two), the box's voxels in each.
        for leaf in cells_between(lo >> 3i32, hi >> 3i32) {
            let origin = leaf << 3i32;
            let Some(&i) = index.get(&origin.to_array()) else {
                continue;
            };
            for v in cells_between(lo.max(origin), hi.min(origin + 7)) {
                let p = v.as_vec3() * voxel;
                if (p - a).dot(normal).abs() > reach {
                    continue;
                }
                let d = triangle_distance(p, tri, &mesh.vertices);
                if d <= reach {
                    work[i].offer(voxel_bit(v), d, t);
                }
            }
        }
    });
    (origins, work)
}

/// What finds a voxel's nearest triangle from its neighbours'.
struct Near<'a> {
    mesh: &'a TriMesh,
    fans: &'a Fans,
}

impl Near<'_> {
    /// From triangle `t` at distance `d` from `p`, the nearest triangle reached by stepping to
    /// a nearer one across an edge, then (where the nearest point is a corner, which edges can
    /// walk around without getting nearer) to one around a corner; and its distance.
    fn descend(&self, p: Vec3, mut t: u32, mut d: f32) -> (f32, u32) {
        let triangles = &self.mesh.triangles;
        let mut corners = true;
        for _ in 0..DESCENT {
            let tri = triangles[t as usize];
            let mut best = (d, t);
            let offer = |u: u32, best: &mut (f32, u32)| {
                let e = triangle_distance(p, triangles[u as usize], &self.mesh.vertices);
                if e < best.0 || (e == best.0 && u < best.1) {
                    *best = (e, u);
                }
            };
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                // The triangles across edge ab: those around a that also have b.
                let across = self
                    .fans
                    .around(a)
                    .iter()
                    .filter(|&&u| u != t && triangles[u as usize].contains(&b));
                across.for_each(|&u| offer(u, &mut best));
            }
            if best.1 == t && corners {
                corners = false;
                for &v in &tri {
                    self.fans
                        .around(v)
                        .iter()
                        .for_each(|&u| offer(u, &mut best));
                }
            }
            if best.1 == t {
                break;
            }
            (d, t) = best;
        }
        (d, t)
    }
}

/// The unknown voxels of leaf `i` next to a known one within the band: each the nearest
/// triangle reached from its known neighbours' nearest ones, with their sign.
fn grow(
    i: usize,
    origin: [i32; 3],
    index: &FxHashMap<[i32; 3], usize>,
    work: &[Work],
    near: &Near,
    voxel: f32,
) -> Vec<(usize, f32, u32)> {
    let band = HALF_WIDTH_VOXELS * voxel;
    let mut found = Vec::new();
    let here = &work[i];
    for n in 0..512 {
        if here.get(n).is_some() {
            continue;
        }
        let v = IVec3::from(origin) + offset(n);
        let p = position(origin, n, voxel);
        let mut best: Option<(f32, u32, bool)> = None;
        let mut tried = [u32::MAX; 6];
        for (k, step) in STEPS.into_iter().enumerate() {
            let u = v + step;
            let leaf = if (u & !7) == IVec3::from(origin) {
                here
            } else {
                match index.get(&(u & !7).to_array()) {
                    Some(&j) => &work[j],
                    None => continue,
                }
            };
            // A voxel beyond the band leads nowhere the band's nearer voxels do not.
            let Some((d, t)) = leaf.get(voxel_bit(u)).filter(|(d, _)| d.abs() < band) else {
                continue;
            };
            if tried[..k].contains(&t) {
                continue;
            }
            tried[k] = t;
            let e = triangle_distance(p, near.mesh.triangles[t as usize], &near.mesh.vertices);
            if best.is_none_or(|(b, bt, _)| e < b || (e == b && t < bt)) {
                best = Some((e, t, d < 0.0));
            }
        }
        if let Some((e, t, inside)) = best {
            let (e, t) = near.descend(p, t, e);
            found.push((n, if inside { -e } else { e }, t));
        }
    }
    found
}

/// The leaf at `origin` from its voxels' distances (NaN: unknown, beyond the band): active
/// where within the band, the others signed by their known neighbours within the leaf; None
/// when no voxel is active.
fn leaf(origin: [i32; 3], distance: &[f32; 512], half_width: f32) -> Option<(VdbLeaf, Vec<f32>)> {
    let mut active = [0u64; 8];
    let mut values = Vec::new();
    // Signs: 1 outside, -1 inside, 0 unknown.
    let mut sign = [0i8; 512];
    for (n, &d) in distance.iter().enumerate() {
        if d.is_nan() {
            continue;
        }
        sign[n] = if d < 0.0 { -1 } else { 1 };
        if d.abs() < half_width {
            active[n >> 6] |= 1 << (n & 63);
            values.push(d);
        }
    }
    if values.is_empty() {
        return None;
    }
    // Unknown voxels lie beyond the band, as do their known neighbours (by more than a voxel):
    // a flood from the known ones within the leaf signs them all (the leaf is connected, so
    // every unknown region borders a known voxel).
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

/// The points of the box from `lo` to `hi`, both included.
fn cells_between(lo: IVec3, hi: IVec3) -> impl Iterator<Item = IVec3> {
    (lo.x..=hi.x).flat_map(move |x| {
        (lo.y..=hi.y).flat_map(move |y| (lo.z..=hi.z).map(move |z| IVec3::new(x, y, z)))
    })
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
