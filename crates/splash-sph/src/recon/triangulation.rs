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

use super::band::{BRICK, Band, brick_of, local_index, local_vertices};
use super::budget;
use super::field_sampling::{BrickValues, vertex_position};
use super::halo::{Halo, neighbour_slot, offset, owns_inside_corner};
use crate::error::{Error, Result};
use crate::mesh::TriMesh;
use crate::mesh::marching_cubes::{
    case_index, cases, crossing_normal, edge_axis, edge_corners, edge_crossing,
};

/// The edge vertices owned by one brick: bit `3 * local_index + axis` marks an edge that holds
/// one, numbered in bit order from `first`; and where the brick's triangles start.
struct BrickEdges {
    bits: [u64; 24],
    /// Vertices in the words before each word.
    ranks: [u32; 24],
    first: u32,
    vertices: u32,
    triangles: usize,
    first_triangle: usize,
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

/// Triangulates the band; `budget` is given the mesh's bytes ([`mesh_bytes`]) once its
/// vertices and triangles are counted, before the mesh is allocated. Each brick's vertices and
/// triangles are written straight into their places in the mesh, counted by a first pass.
pub fn triangulate(
    band: &Band,
    values: &BrickValues,
    budget: impl FnOnce(u64) -> Result<()>,
) -> Result<Triangulation> {
    let cell = band.cell;
    let lows = values.inside_lows(band);
    // Only bricks with edge vertices or triangles keep an edge table.
    let counted: Vec<(Option<Box<BrickEdges>>, usize)> = band
        .bricks
        .par_iter()
        .map_init(Halo::new, |halo, &brick| {
            if !owns_inside_corner(band, &lows, brick) {
                return (None, 0);
            }
            halo.fill(band, values, brick);
            let (e, cells) = count_brick(halo);
            let keep = e.vertices > 0 || e.triangles > 0;
            (keep.then(|| Box::new(e)), cells)
        })
        .collect();
    let surface_cells = counted.iter().map(|(_, n)| n).sum();
    let mut edges: Vec<Option<Box<BrickEdges>>> = counted.into_iter().map(|(e, _)| e).collect();
    let (mut next, mut triangles) = (0u32, 0usize);
    let mut brick_vertices = Vec::with_capacity(edges.len());
    for e in edges.iter_mut().flatten() {
        (e.first, e.first_triangle) = (next, triangles);
        next = next.checked_add(e.vertices).ok_or_else(|| {
            Error::limit(format!(
                "the mesh would have more than {} vertices, the most its indices can \
                 number; use a larger cell",
                u32::MAX
            ))
        })?;
        triangles += e.triangles;
        if e.vertices > 0 {
            brick_vertices.push(e.first as usize..next as usize);
        }
    }
    budget(mesh_bytes(
        next.into(),
        triangles as u64,
        edges.iter().flatten().count() as u64,
    ))?;
    let what = || format!("a mesh of {next} vertices and {triangles} triangles");
    let mut mesh = TriMesh {
        vertices: budget::try_filled(next as usize, Vec3::ZERO, what)?,
        normals: budget::try_filled(next as usize, Vec3::ZERO, what)?,
        triangles: budget::try_filled(triangles, [0; 3], what)?,
    };
    // Each brick's part of the three arrays, in brick order.
    let mut parts = Vec::with_capacity(edges.len());
    let (mut v, mut n, mut t) = (
        mesh.vertices.as_mut_slice(),
        mesh.normals.as_mut_slice(),
        mesh.triangles.as_mut_slice(),
    );
    for (b, e) in edges.iter().enumerate() {
        let Some(e) = e else { continue };
        let (k, m) = (e.vertices as usize, e.triangles);
        let (vh, vt) = std::mem::take(&mut v).split_at_mut(k);
        let (nh, nt) = std::mem::take(&mut n).split_at_mut(k);
        let (th, tt) = std::mem::take(&mut t).split_at_mut(m);
        parts.push((b, vh, nh, th));
        (v, n, t) = (vt, nt, tt);
    }
    parts
        .into_par_iter()
        .for_each_init(Halo::new, |halo, (b, positions, normals, tris)| {
            let brick = band.bricks[b];
            halo.fill(band, values, brick);
            edge_vertices(halo, brick, cell, positions, normals);
            brick_triangles(halo, &edges, tris);
        });
    Ok(Triangulation {
        mesh,
        brick_vertices,
        surface_cells,
    })
}

/// Peak heap of the triangulation of a mesh of `vertices` and `triangles` over `bricks` with
/// edge tables: the edge tables, the mesh, then the field normals' gradients (12 bytes a
/// vertex).
pub fn mesh_bytes(vertices: u64, triangles: u64, bricks: u64) -> u64 {
    let per_vertex = 2 * size_of::<Vec3>() as u64 + size_of::<Vec3>() as u64;
    let per_triangle = size_of::<[u32; 3]>() as u64;
    vertices
        .saturating_mul(per_vertex)
        .saturating_add(triangles.saturating_mul(per_triangle))
        .saturating_add(bricks.saturating_mul(PER_BRICK_EDGES))
}

/// The edge table of a brick (which of the sign-changing edges leaving its vertices in +x,
/// +y, +z have a vertex: those where at least one of the four cells around the edge is
/// triangulated), the number of its triangles and of its surface cells.
fn count_brick(halo: &Halo) -> (BrickEdges, usize) {
    let mut edges = BrickEdges {
        bits: [0; 24],
        ranks: [0; 24],
        first: 0,
        vertices: 0,
        triangles: 0,
        first_triangle: 0,
    };
    let mut cells = 0;
    for l in local_vertices() {
        for (axis, _, _) in vertex_edges(halo, l) {
            let bit = 3 * local_index(l) + axis;
            edges.bits[bit / 64] |= 1 << (bit % 64);
        }
        if halo.complete(l) {
            let n = cases()[case_index(&halo.corners(l))].triangles().len();
            edges.triangles += n;
            cells += usize::from(n > 0);
        }
    }
    let mut count = 0;
    for (rank, bits) in edges.ranks.iter_mut().zip(&edges.bits) {
        *rank = count;
        count += bits.count_ones();
    }
    edges.vertices = count;
    (edges, cells)
}

/// The positions and grid normals of the vertices [`count_brick`] marked, in bit order.
fn edge_vertices(
    halo: &Halo,
    brick: IVec3,
    cell: f32,
    positions: &mut [Vec3],
    normals: &mut [Vec3],
) {
    let mut k = 0;
    for l in local_vertices() {
        for (axis, v0, v1) in vertex_edges(halo, l) {
            let e = IVec3::AXES[axis];
            let p0 = vertex_position(brick * BRICK + l, cell);
            let (p, t) = edge_crossing(p0, axis, cell, v0, v1);
            let (g0, g1) = (halo.gradient(l, cell), halo.gradient(l + e, cell));
            positions[k] = p;
            normals[k] = crossing_normal(g0, g1, t, axis, v0, v1);
            k += 1;
        }
    }
    debug_assert_eq!(k, positions.len(), "the vertices counted");
}

/// The edges leaving vertex `l` in +x, +y, +z that carry a mesh vertex: the field changes sign
/// along them and one of the four cells around them is triangulated. Yields (axis, value at
/// `l`, value at the other end).
fn vertex_edges(halo: &Halo, l: IVec3) -> impl Iterator<Item = (usize, f32, f32)> + '_ {
    let v0 = halo.at(l);
    (0..3).filter_map(move |axis| {
        let v1 = halo.at(l + IVec3::AXES[axis]);
        let crossed = !v0.is_nan() && !v1.is_nan() && (v0 < 0.0) != (v1 < 0.0);
        (crossed && edge_in_surface_cell(halo, l, axis)).then_some((axis, v0, v1))
    })
}

fn edge_in_surface_cell(halo: &Halo, l: IVec3, axis: usize) -> bool {
    let (u, v) = (IVec3::AXES[(axis + 1) % 3], IVec3::AXES[(axis + 2) % 3]);
    [l, l - u, l - v, l - u - v]
        .into_iter()
        .any(|c| halo.complete(c))
}

/// The triangles of the brick's surface cells, into `out` (as many as [`count_brick`] found).
fn brick_triangles(halo: &Halo, edges: &[Option<Box<BrickEdges>>], out: &mut [[u32; 3]]) {
    let mut k = 0;
    for l in local_vertices() {
        if !halo.complete(l) {
            continue;
        }
        let case = case_index(&halo.corners(l));
        for t in cases()[case].triangles() {
            out[k] = t.map(|e| {
                let e = e as usize;
                let owner = l + offset(edge_corners(e).0);
                let d = brick_of(owner);
                let b = halo.neighbours[neighbour_slot(d)]
                    .expect("a complete cell's corners lie in existing bricks");
                let owned = edges[b].as_ref().expect("a crossed edge has a vertex");
                owned.id(local_index(owner - d * BRICK), edge_axis(e))
            });
            k += 1;
        }
    }
    debug_assert_eq!(k, out.len(), "the triangles counted");
}
