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

use crate::config::Normals;
use crate::field::ScalarField;
use crate::mesh::TriMesh;
use crate::neighbours::handler_array::HandlerArray;
use crate::neighbours::neighbourhood::Neighbourhood;
use crate::recon::bricks::brick_values::TASK_BRICKS;

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

/// Bits per coordinate of a cell within a brick's vertices in the sort keys (they span at
/// most 9 cells), and of a vertex's index within its brick.
const COORD_BITS: u32 = 8;
const INDEX_BITS: u32 = 16;

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
    let TriMesh {
        vertices, normals, ..
    } = mesh;
    normals.resize(vertices.len(), Vec3::ZERO);
    // Each brick's vertices with its normals, written in place: the ranges are in order.
    let mut rest = &mut normals[..];
    let mut done = 0;
    let bricks: Vec<(&[Vec3], &mut [Vec3])> = bricks
        .iter()
        .map(|range| {
            let (_, tail) = std::mem::take(&mut rest).split_at_mut(range.start - done);
            let (own, tail) = tail.split_at_mut(range.len());
            (rest, done) = (tail, range.end);
            (&vertices[range.clone()], own)
        })
        .collect();
    bricks
        .into_par_iter()
        .with_max_len(TASK_BRICKS)
        .for_each_init(
            || ([(); 3].map(|_| Neighbourhood::default()), Vec::new()),
            |([brick_near, block_near, cell_near], order), (brick, normals)| {
                let (lo, hi) = brick.iter().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), &v| {
                    (lo.min(v), hi.max(v))
                });
                brick_near.gather_box(handlers, lo, hi, reach, own_reach);
                // The brick's vertices by cell, cells by block of 4³: each block and each cell
                // narrows the list once, as the field sampling does. One u64 key per vertex
                // sorts them: block, then cell (z, y, x each), then index.
                let cell_of = |v: Vec3| ((v - lo) / cell).floor().as_ivec3();
                let pack = |c: IVec3| {
                    debug_assert!(c.cmpge(IVec3::ZERO).all() && c.max_element() < 1 << COORD_BITS);
                    let c = c.as_uvec3().to_array().map(u64::from);
                    (c[2] << COORD_BITS | c[1]) << COORD_BITS | c[0]
                };
                let key = |c: IVec3| {
                    pack(c.div_euclid(IVec3::splat(BLOCK))) << (3 * COORD_BITS) | pack(c)
                };
                debug_assert!(brick.len() <= 1 << INDEX_BITS);
                order.clear();
                order.extend(
                    brick
                        .iter()
                        .enumerate()
                        .map(|(i, &v)| key(cell_of(v)) << INDEX_BITS | i as u64),
                );
                order.sort_unstable();
                let cell_bits = INDEX_BITS;
                let block_bits = INDEX_BITS + 3 * COORD_BITS;
                let index = |k: u64| (k & ((1 << INDEX_BITS) - 1)) as usize;
                for block in order.chunk_by(|a, b| a >> block_bits == b >> block_bits) {
                    let c = cell_of(brick[index(block[0])]);
                    let blo = lo + (c.div_euclid(IVec3::splat(BLOCK)) * BLOCK).as_vec3() * cell;
                    let bhi = blo + BLOCK as f32 * cell;
                    block_near.filter_box(brick_near, blo, bhi, reach, own_reach);
                    for run in block.chunk_by(|a, b| a >> cell_bits == b >> cell_bits) {
                        let clo = lo + cell_of(brick[index(run[0])]).as_vec3() * cell;
                        cell_near.filter_box(block_near, clo, clo + cell, reach, own_reach);
                        for &k in run {
                            let i = index(k);
                            if let Some(n) =
                                field.gradient(cell_near, brick[i] - clo).try_normalize()
                            {
                                normals[i] = n;
                            }
                        }
                    }
                }
            },
        );
}
