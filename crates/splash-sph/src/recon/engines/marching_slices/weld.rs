//! One seamless mesh from the blocks' meshes. A vertex on a face shared by two blocks is made
//! by both, from the same corner values (each block looks up exactly the particles in reach,
//! in the same order), so it is welded by its edge: vertices are ordered by edge as the
//! narrow band numbers them (brick, vertex in brick, axis), and equal edges become one.
//! Nothing depends on the thread count or on a distance tolerance.

use std::ops::Range;

use glam::IVec3;
use rayon::prelude::*;

use super::super::prepared::triangles_and_normals;
use super::marching::BlockMesh;
use crate::config::Params;
use crate::error::{Error, Result};
use crate::field::ScalarField;
use crate::mesh::TriMesh;
use crate::neighbours::handler_array::HandlerArray;
use crate::recon::bricks::band::{BRICK, brick_of, local_index};
use crate::recon::budget;
use crate::recon::stages::triangulation::Triangulation;
use crate::report::Stages;

/// Sort key of an edge: its brick in (z, y, x) order, then its lower corner in the brick,
/// then its axis.
type EdgeKey = (i32, i32, i32, u32);

fn key((corner, axis): (IVec3, u8)) -> EdgeKey {
    let b = brick_of(corner);
    let local = local_index(corner - b * BRICK) as u32;
    (b.z, b.y, b.x, local * 3 + u32::from(axis))
}

/// The blocks' meshes welded as in [`weld`] (checked against the memory limit with `held`
/// bytes besides them and the blocks' meshes, naming `what`), then their triangles and
/// normals made as every engine's, from `samples`: the last stages of the slices engine and
/// of the surface-following baselines.
#[allow(clippy::too_many_arguments)]
pub(in crate::recon::engines) fn weld_and_finish(
    stages: &mut Stages<'_>,
    params: &Params,
    field: &dyn ScalarField,
    samples: &HandlerArray,
    held: u64,
    meshes: Vec<BlockMesh>,
    surface_cells: usize,
    what: &str,
) -> Result<Triangulation> {
    triangles_and_normals(
        stages,
        params,
        field,
        || {
            let held = held.saturating_add(
                meshes
                    .iter()
                    .map(|m| m.heap_bytes() as u64)
                    .fold(0, u64::saturating_add),
            );
            weld(meshes, surface_cells, |mesh| {
                budget::check(params, held.saturating_add(mesh), || what.into()).map(drop)
            })
        },
        || Ok(samples),
    )
}

/// The blocks' meshes as one, with the `surface_cells` the blocks visited.
/// `budget` is given the bytes of the weld and the mesh before they are allocated.
pub fn weld(
    blocks: Vec<BlockMesh>,
    surface_cells: usize,
    budget: impl FnOnce(u64) -> Result<()>,
) -> Result<Triangulation> {
    let vertices: usize = blocks.iter().map(|m| m.positions.len()).sum();
    let triangles: usize = blocks.iter().map(|m| m.triangles.len()).sum();
    // Order (16) and remap (4) per block vertex; the mesh's positions and normals (24) and
    // triangles (12).
    budget(
        (vertices as u64)
            .saturating_mul(44)
            .saturating_add(triangles as u64 * 12),
    )?;
    if u32::try_from(vertices).is_err() {
        return Err(Error::limit(format!(
            "the blocks' meshes have {vertices} vertices, more than a mesh's indices can \
             number; use a larger cell"
        )));
    }
    let with_normals = blocks.iter().any(|b| !b.normals.is_empty());
    // (edge key, block, vertex in block), in block order.
    let mut order: Vec<(EdgeKey, u32, u32)> =
        budget::try_vec(vertices, || format!("welding {vertices} vertices"))?;
    order.extend(blocks.iter().enumerate().flat_map(|(b, m)| {
        m.edges
            .iter()
            .enumerate()
            .map(move |(v, &e)| (key(e), b as u32, v as u32))
    }));
    order.par_sort_unstable();
    let mut first = Vec::with_capacity(blocks.len());
    let mut total = 0usize;
    for b in &blocks {
        first.push(total);
        total += b.positions.len();
    }
    let mut remap = budget::try_filled(total, 0u32, || format!("welding {total} vertices"))?;
    let mut mesh = TriMesh::default();
    let mut brick_vertices: Vec<Range<usize>> = Vec::new();
    let mut last: Option<EdgeKey> = None;
    for &(k, b, v) in &order {
        if last != Some(k) {
            let id = mesh.vertices.len();
            let m = &blocks[b as usize];
            mesh.vertices.push(m.positions[v as usize]);
            if with_normals {
                mesh.normals.push(m.normals[v as usize]);
            }
            let same_brick = last.is_some_and(|l| (l.0, l.1, l.2) == (k.0, k.1, k.2));
            match brick_vertices.last_mut() {
                Some(r) if same_brick => r.end = id + 1,
                _ => brick_vertices.push(id..id + 1),
            }
            last = Some(k);
        }
        remap[first[b as usize] + v as usize] = mesh.vertices.len() as u32 - 1;
    }
    mesh.triangles = blocks
        .iter()
        .enumerate()
        .flat_map(|(b, m)| {
            let base = first[b];
            let remap = &remap;
            m.triangles
                .iter()
                .map(move |t| t.map(|v| remap[base + v as usize]))
        })
        .collect();
    Ok(Triangulation {
        mesh,
        brick_vertices,
        surface_cells,
    })
}
