//! Vertex normals from the field's own gradient at each mesh vertex (the gradient every field
//! defines), rather than from differences of the sampled grid values, which a cell of 2r
//! smooths over (those stay available as `normals = "grid"`).
//!
//! Gathered as the field is (`field_sampling.rs`): once per brick, narrowed to each cube of
//! 2×2×2 cells, and the cube's list reused by every vertex in it.

use std::ops::Range;

use glam::{IVec3, Vec3};
use rayon::prelude::*;

use super::handler_array::HandlerArray;
use super::neighbourhood::Neighbourhood;
use crate::config::Normals;
use crate::field::ScalarField;
use crate::mesh::TriMesh;

/// Gives an engine's mesh, which comes with its grid normals, the normals `kind` asks for.
/// `bricks` are the ranges of vertices that each lie within one brick.
pub fn set_normals<F: ScalarField + ?Sized>(
    kind: Normals,
    mesh: &mut TriMesh,
    bricks: &[Range<usize>],
    cell: f32,
    handlers: &HandlerArray,
    field: &F,
) {
    match kind {
        Normals::Field => field_normals(mesh, bricks, cell, handlers, field),
        Normals::Grid => {}
        Normals::None => mesh.normals = Vec::new(),
    }
}

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
        .map_init(
            || ([(); 2].map(|_| Neighbourhood::default()), Vec::new()),
            |([brick_near, group_near], order), range| {
                let brick = &vertices[range.clone()];
                let (lo, hi) = brick.iter().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), &v| {
                    (lo.min(v), hi.max(v))
                });
                brick_near.gather_box(handlers, lo, hi, reach, own_reach);
                // The brick's vertices by cube of 2 cells, so that each cube is gathered once.
                let group = |v: Vec3| ((v - lo) / (2.0 * cell)).floor().as_ivec3();
                order.clear();
                order.extend(0..brick.len());
                order.sort_unstable_by_key(|&i| {
                    let g = group(brick[i]);
                    (g.z, g.y, g.x)
                });
                let mut out = vec![Vec3::ZERO; brick.len()];
                for run in order.chunk_by(|&a, &b| group(brick[a]) == group(brick[b])) {
                    let g: IVec3 = group(brick[run[0]]);
                    let glo = lo + g.as_vec3() * 2.0 * cell;
                    group_near.filter_box(brick_near, glo, glo + 2.0 * cell, reach, own_reach);
                    for &i in run {
                        out[i] = field.gradient(group_near, brick[i] - glo);
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
