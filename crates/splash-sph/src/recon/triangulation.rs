//! Triangulation of the surface cells (Sec. 4.2): a cell is triangulated only when all eight
//! corners are surface vertices, which also keeps the inner rim of the band from forming a
//! second layer. Each intersected edge gets one vertex, owned by the edge's lower end and
//! shared by every cell around it.
//!
//! Unlike the paper's serial pass, bricks are triangulated in parallel, in two passes so that
//! vertex numbers do not depend on the thread count: the first creates each brick's edge
//! vertices, a prefix sum numbers them, the second emits triangles.

use std::ops::Range;

use glam::{IVec3, Vec3};
use rayon::prelude::*;

use super::band::{BRICK, Band, brick_of, local_index};
use super::budget;
use super::field_sampling::{BrickValues, vertex_position};
use super::halo::{Halo, neighbour_slot, offset, owns_inside_corner};
use crate::error::{Error, Result};
use crate::mesh::TriMesh;
use crate::mesh::marching_cubes::{
    case_index, cases, crossing_normal, edge_axis, edge_corners, edge_crossing,
};

/// The edge vertices owned by one brick: bit `3 * local_index + axis` marks an edge that holds
/// one, numbered in bit order from `first`.
struct BrickEdges {
    bits: [u64; 24],
    /// Vertices in the words before each word.
    ranks: [u32; 24],
    first: u32,
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
}

impl BrickEdges {
    fn id(&self, local: usize, axis: usize) -> u32 {
        let bit = 3 * local + axis;
        let (w, b) = (bit / 64, bit % 64);
        debug_assert!(self.bits[w] >> b & 1 == 1, "edge without a vertex");
        self.first + self.ranks[w] + (self.bits[w] & ((1u64 << b) - 1)).count_ones()
    }
}

pub struct Triangulation {
    pub mesh: TriMesh,
    /// The mesh's vertices of each brick: all lie within its cells.
    pub brick_vertices: Vec<Range<usize>>,
    /// Cells with all eight corners in the band that the surface crosses.
    pub surface_cells: usize,
}

/// Bytes the triangulation holds per brick besides its vertices: the edge table.
pub const PER_BRICK_EDGES: u64 = size_of::<BrickEdges>() as u64;

/// Triangulates the band; `budget` is given the mesh's bytes (the per-brick parts and the
/// mesh they are copied into, [`mesh_bytes`]) once its vertices and triangles are counted,
/// before the mesh is allocated.
pub fn triangulate(
    band: &Band,
    values: &BrickValues,
    budget: impl FnOnce(u64) -> Result<()>,
) -> Result<Triangulation> {
    let cell = band.cell;
    let lows = values.inside_lows(band);
    // Only bricks with edge vertices keep an edge table.
    let mut edges: Vec<Option<Box<BrickEdges>>> = band
        .bricks
        .par_iter()
        .map_init(Halo::new, |halo, &brick| {
            if !owns_inside_corner(band, &lows, brick) {
                return None;
            }
            halo.fill(band, values, brick);
            let e = edge_vertices(halo, brick, cell);
            (!e.positions.is_empty()).then(|| Box::new(e))
        })
        .collect();
    let mut next = 0u32;
    let mut brick_vertices = Vec::with_capacity(edges.len());
    for e in edges.iter_mut().flatten() {
        e.first = next;
        next = u32::try_from(e.positions.len())
            .ok()
            .and_then(|n| next.checked_add(n))
            .ok_or_else(|| {
                Error::limit(format!(
                    "the mesh would have more than {} vertices, the most its indices can \
                     number; use a larger cell",
                    u32::MAX
                ))
            })?;
        brick_vertices.push(e.first as usize..next as usize);
    }
    let per_brick: Vec<(Vec<[u32; 3]>, usize)> = band
        .bricks
        .par_iter()
        .map_init(Halo::new, |halo, &brick| {
            if !owns_inside_corner(band, &lows, brick) {
                return (Vec::new(), 0);
            }
            halo.fill(band, values, brick);
            brick_triangles(halo, &edges)
        })
        .collect();
    let surface_cells = per_brick.iter().map(|(_, n)| n).sum();
    let triangles: usize = per_brick.iter().map(|(t, _)| t.len()).sum();
    budget(mesh_bytes(
        next.into(),
        triangles as u64,
        brick_vertices.len() as u64,
    ))?;
    let what = || format!("a mesh of {next} vertices and {triangles} triangles");
    let mut mesh = TriMesh {
        vertices: budget::try_vec(next as usize, what)?,
        normals: budget::try_vec(next as usize, what)?,
        triangles: budget::try_vec(triangles, what)?,
    };
    for e in edges.iter().flatten() {
        mesh.vertices.extend_from_slice(&e.positions);
        mesh.normals.extend_from_slice(&e.normals);
    }
    for (t, _) in &per_brick {
        mesh.triangles.extend_from_slice(t);
    }
    Ok(Triangulation {
        mesh,
        brick_vertices,
        surface_cells,
    })
}

/// Peak heap of the triangulation of a mesh of `vertices` and `triangles` over `bricks`:
/// per brick its edge table, its vertices' positions and normals and its triangles, then the
/// mesh they are copied into, then the field normals' gradients (12 bytes a vertex).
pub fn mesh_bytes(vertices: u64, triangles: u64, bricks: u64) -> u64 {
    let per_vertex = 2 * 2 * size_of::<Vec3>() as u64 + size_of::<Vec3>() as u64;
    let per_triangle = 2 * size_of::<[u32; 3]>() as u64;
    vertices
        .saturating_mul(per_vertex)
        .saturating_add(triangles.saturating_mul(per_triangle))
        .saturating_add(bricks.saturating_mul(PER_BRICK_EDGES))
}

/// Vertices on the sign-changing edges leaving this brick's vertices in +x, +y, +z, where at
/// least one of the four cells around the edge is triangulated.
fn edge_vertices(halo: &Halo, brick: IVec3, cell: f32) -> BrickEdges {
    let mut edges = BrickEdges {
        bits: [0; 24],
        ranks: [0; 24],
        first: 0,
        positions: Vec::new(),
        normals: Vec::new(),
    };
    for z in 0..BRICK {
        for y in 0..BRICK {
            for x in 0..BRICK {
                let l = IVec3::new(x, y, z);
                let v0 = halo.at(l);
                if v0.is_nan() {
                    continue;
                }
                for axis in 0..3 {
                    let e = IVec3::AXES[axis];
                    let v1 = halo.at(l + e);
                    if v1.is_nan()
                        || (v0 < 0.0) == (v1 < 0.0)
                        || !edge_in_surface_cell(halo, l, axis)
                    {
                        continue;
                    }
                    let bit = 3 * local_index(l) + axis;
                    edges.bits[bit / 64] |= 1 << (bit % 64);
                    let p0 = vertex_position(brick * BRICK + l, cell);
                    let (p, t) = edge_crossing(p0, axis, cell, v0, v1);
                    edges.positions.push(p);
                    let (g0, g1) = (halo.gradient(l, cell), halo.gradient(l + e, cell));
                    edges.normals.push(crossing_normal(g0, g1, t, axis, v0, v1));
                }
            }
        }
    }
    let mut count = 0;
    for (rank, bits) in edges.ranks.iter_mut().zip(&edges.bits) {
        *rank = count;
        count += bits.count_ones();
    }
    edges
}

fn edge_in_surface_cell(halo: &Halo, l: IVec3, axis: usize) -> bool {
    let (u, v) = (IVec3::AXES[(axis + 1) % 3], IVec3::AXES[(axis + 2) % 3]);
    [l, l - u, l - v, l - u - v]
        .into_iter()
        .any(|c| halo.complete(c))
}

fn brick_triangles(halo: &Halo, edges: &[Option<Box<BrickEdges>>]) -> (Vec<[u32; 3]>, usize) {
    let mut triangles = Vec::new();
    let mut surface_cells = 0;
    for z in 0..BRICK {
        for y in 0..BRICK {
            for x in 0..BRICK {
                let l = IVec3::new(x, y, z);
                if !halo.complete(l) {
                    continue;
                }
                let case = case_index(&halo.corners(l));
                let tris = cases()[case].triangles();
                if tris.is_empty() {
                    continue;
                }
                surface_cells += 1;
                for t in tris {
                    triangles.push(t.map(|e| {
                        let e = e as usize;
                        let owner = l + offset(edge_corners(e).0);
                        let d = brick_of(owner);
                        let b = halo.neighbours[neighbour_slot(d)]
                            .expect("a complete cell's corners lie in existing bricks");
                        let owned = edges[b].as_ref().expect("a crossed edge has a vertex");
                        owned.id(local_index(owner - d * BRICK), edge_axis(e))
                    }));
                }
            }
        }
    }
    (triangles, surface_cells)
}
