//! Vertex normals from the field's own gradient at each mesh vertex (the gradient every field
//! defines), rather than from differences of the sampled grid values, which a cell of 2r
//! smooths over (those stay available as `normals = "grid"`).
//!
//! Gathered as the field is (`field_sampling.rs`): once per brick, narrowed to each block of
//! 4³ cells and then to each cell, whose list serves every vertex in it.

use std::borrow::Borrow;
use std::ops::Range;

use crate::error::Result;

use glam::{IVec3, Vec3};
use rayon::prelude::*;

use super::brick_values::TASK_BRICKS;
use crate::config::Normals;
use crate::field::ScalarField;
use crate::mesh::TriMesh;
use crate::neighbours::handler_array::HandlerArray;
use crate::neighbours::neighbourhood::Neighbourhood;

/// Gives an engine's mesh, which comes with its grid normals, the normals `kind` asks for.
/// `bricks` are the ranges of vertices that each lie within one brick; `handlers` gives the
/// particles to gather, asked for only by the field's normals.
pub fn set_normals<F: ScalarField + ?Sized, H: Borrow<HandlerArray>>(
    kind: Normals,
    mesh: &mut TriMesh,
    bricks: &[Range<usize>],
    cell: f32,
    handlers: impl FnOnce() -> Result<H>,
    field: &F,
) -> Result<()> {
    match kind {
        Normals::Field => field_normals(mesh, bricks, cell, handlers()?.borrow(), field),
        Normals::Grid => {}
        Normals::None => mesh.normals = Vec::new(),
    }
    Ok(())
}

/// Cells per side of the middle level of narrowing.
const BLOCK: i32 = 4;

/// Replaces each vertex normal by the normalised field gradient there, where it is not zero
/// (a vertex then keeps its grid normal).
fn field_normals<F: ScalarField + ?Sized>(
    mesh: &mut TriMesh,
    bricks: &[Range<usize>],
    cell: f32,
    handlers: &HandlerArray,
    field: &F,
) {
    let reach = field.support();
    let own_reach = field.reach_channel();
    let vertices = &mesh.vertices;
    let normals: Vec<(Range<usize>, Vec<Vec3>)> = bricks
        .par_iter()
        .with_max_len(TASK_BRICKS)
        .map_init(
            || ([(); 3].map(|_| Neighbourhood::default()), Vec::new()),
            |([brick_near, block_near, cell_near], order), range| {
                let brick = &vertices[range.clone()];
                let (lo, hi) = brick.iter().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), &v| {
                    (lo.min(v), hi.max(v))
                });
                brick_near.gather_box(handlers, lo, hi, reach, own_reach);
                // The brick's vertices by cell, cells by block of 4³: each block and each
                // cell narrows the list once, as the field sampling does.
                let cell_of = |v: Vec3| ((v - lo) / cell).floor().as_ivec3();
                let block_of = |c: IVec3| c.div_euclid(IVec3::splat(BLOCK));
                order.clear();
                order.extend((0..brick.len()).map(|i| (cell_of(brick[i]), i)));
                order.sort_unstable_by_key(|&(c, i)| {
                    let b = block_of(c);
                    (b.z, b.y, b.x, c.z, c.y, c.x, i)
                });
                let mut out = vec![Vec3::ZERO; brick.len()];
                for block in order.chunk_by(|a, b| block_of(a.0) == block_of(b.0)) {
                    let blo = lo + (block_of(block[0].0) * BLOCK).as_vec3() * cell;
                    let bhi = blo + BLOCK as f32 * cell;
                    block_near.filter_box(brick_near, blo, bhi, reach, own_reach);
                    for run in block.chunk_by(|a, b| a.0 == b.0) {
                        let clo = lo + run[0].0.as_vec3() * cell;
                        cell_near.filter_box(block_near, clo, clo + cell, reach, own_reach);
                        for &(_, i) in run {
                            out[i] = field.gradient(cell_near, brick[i] - clo);
                        }
                    }
                }
                (range.clone(), out)
            },
        )
        .collect();
    mesh.normals.resize(mesh.vertices.len(), Vec3::ZERO);
    for (range, gradients) in normals {
        for (n, g) in mesh.normals[range].iter_mut().zip(gradients) {
            if let Some(g) = g.try_normalize() {
                *n = g;
            }
        }
    }
}
