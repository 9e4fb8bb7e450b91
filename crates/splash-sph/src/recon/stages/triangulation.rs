//! Triangulation of the surface cells (Sec. 4.2): a cell is triangulated only when all eight
//! corners are surface vertices, which also keeps the inner rim of the band from forming a
//! second layer. Each intersected edge gets one vertex, owned by the edge's lower end and
//! shared by every cell around it.
//!
//! Unlike the paper's serial pass, bricks are triangulated in parallel, in two passes so that
//! vertex numbers do not depend on the thread count: the first creates each brick's edge
//! vertices, a prefix sum numbers them, the second emits triangles.

use std::ops::Range;
use std::sync::LazyLock;

use glam::{IVec3, Vec3};
use rayon::prelude::*;

use super::field_sampling::vertex_position;
use crate::error::{Error, Result};
use crate::mesh::TriMesh;
use crate::mesh::marching_cubes::{cases, crossing_normal, edge_axis, edge_corners, edge_crossing};
use crate::recon::bricks::band::{BRICK, Band, brick_of, local_index, local_vertex};
use crate::recon::bricks::brick_neighbours::NeighbourWalk;
use crate::recon::bricks::brick_signs::Signs;
use crate::recon::bricks::brick_values::BrickValues;
use crate::recon::bricks::brick_values::TASK_BRICKS;
use crate::recon::bricks::edge_tables::{BrickEdges, EdgeTables, PER_BRICK_EDGES};
use crate::recon::bricks::halo::{Halo, neighbour_slot, offset};
use crate::recon::bricks::surface_cells::BrickCells;
use crate::recon::budget;

pub struct Triangulation {
    pub mesh: TriMesh,
    /// The mesh's vertices of each brick: all lie within its cells.
    pub brick_vertices: Vec<Range<usize>>,
    /// Cells with all eight corners in the band that the surface crosses.
    pub surface_cells: usize,
}

/// Triangulates the band whose values have the sign planes `signs` and whose bricks have the
/// edge tables `tables`; `budget` is given the bytes of the mesh ([`mesh_bytes`]) and of the
/// sign planes once its vertices and triangles are counted, before the mesh is allocated.
/// Each brick's vertices and triangles are written straight into their places in the mesh.
pub fn triangulate(
    band: &Band,
    values: &BrickValues,
    signs: Signs,
    tables: EdgeTables,
    budget: impl FnOnce(u64) -> Result<()>,
) -> Result<Triangulation> {
    let cell = band.cell;
    let mut edges = tables.0;
    let surface_cells = edges.iter().flatten().map(|e| e.cells as usize).sum();
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
    budget(
        mesh_bytes(
            next.into(),
            triangles as u64,
            edges.iter().flatten().count() as u64,
        )
        .saturating_add(signs.heap_bytes() as u64),
    )?;
    let what = || format!("a mesh of {next} vertices and {triangles} triangles");
    let mut mesh = TriMesh {
        vertices: budget::try_zeroed(next as usize, what)?,
        normals: budget::try_zeroed(next as usize, what)?,
        triangles: budget::try_zeroed(triangles, what)?,
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
        .with_max_len(TASK_BRICKS)
        .for_each_init(
            || {
                (
                    BrickCells::new(),
                    Halo::new(),
                    NeighbourWalk::new(&band.bricks),
                )
            },
            |(cells, halo, walk), (b, positions, normals, tris)| {
                let brick = band.bricks[b];
                cells.fill(band, &signs, walk.around(brick));
                if !positions.is_empty() {
                    let e = edges[b]
                        .as_deref()
                        .expect("a brick with vertices has edges");
                    // Vertices' ends and the central differences at them.
                    let (lo, hi) = e.extent();
                    halo.fill(band, values, &cells.neighbours, lo - 1, hi + 2);
                    edge_vertices(halo, e, brick, cell, positions, normals);
                }
                brick_triangles(cells, &edges, tris);
            },
        );
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

/// The positions and grid normals of the vertices of `edges`, in bit order.
fn edge_vertices(
    halo: &Halo,
    edges: &BrickEdges,
    brick: IVec3,
    cell: f32,
    positions: &mut [Vec3],
    normals: &mut [Vec3],
) {
    let mut k = 0;
    edges.each(|local, axis| {
        let l = local_vertex(local);
        let e = IVec3::AXES[axis];
        let (v0, v1) = (halo.at(l), halo.at(l + e));
        let p0 = vertex_position(brick * BRICK + l, cell);
        let (p, t) = edge_crossing(p0, axis, cell, v0, v1);
        let (g0, g1) = (halo.gradient(l, cell), halo.gradient(l + e, cell));
        positions[k] = p;
        normals[k] = crossing_normal(g0, g1, t, axis, v0, v1);
        k += 1;
    });
    debug_assert_eq!(k, positions.len(), "the vertices counted");
}

/// The triangles of the brick's surface cells, into `out` (as many as its edge table counts).
fn brick_triangles(cells: &BrickCells, edges: &[Option<Box<BrickEdges>>], out: &mut [[u32; 3]]) {
    let owners: [Option<&BrickEdges>; 27] = cells
        .neighbours
        .map(|n| n.and_then(|b| edges[b].as_deref()));
    let own = owners[neighbour_slot(IVec3::ZERO)].expect("a brick with triangles has edges");
    let (table, mut k) = (cases(), 0);
    cells.crossed(|l, case| {
        // Cells off the brick's upper faces own all their edges' vertices in this brick.
        let inner = l.max_element() < BRICK - 1;
        for t in table[case].triangles() {
            out[k] = t.map(|e| {
                let (corner, axis) = EDGE_OWNERS[e as usize];
                let owner = l + corner;
                if inner {
                    return own.id(local_index(owner), axis);
                }
                let d = brick_of(owner);
                let owned = owners[neighbour_slot(d)].expect("a crossed edge has a vertex");
                owned.id(local_index(owner - d * BRICK), axis)
            });
            k += 1;
        }
    });
    debug_assert_eq!(k, out.len(), "the triangles counted");
}

/// Each cell edge's lower corner (which owns its vertex) and axis.
static EDGE_OWNERS: LazyLock<[(IVec3, usize); 12]> =
    LazyLock::new(|| std::array::from_fn(|e| (offset(edge_corners(e).0), edge_axis(e))));
