//! `correct = N`: every engine's Marching Cubes vertices moved along their cube edges onto the
//! field's exact isosurface, by N safeguarded Newton steps (Marching Correctors, Sec. III-D2,
//! [`CrossedEdge::correct`]).
//!
//! Runs on the finished mesh, so it is the same for every engine: a vertex's edge is read back
//! from its position (two coordinates on grid lines, the third strictly between two), and the
//! edge's corners are evaluated again. The particles are gathered once per brick of vertices,
//! narrowed to blocks of 4³ cells and then to the cell whose lowest corner starts the edge, as
//! the field normals gather them. A vertex that the steps leave farther from the level than
//! linear interpolation put it keeps its place, so no vertex's |f − iso| grows.

use std::ops::Range;

use glam::{IVec3, Vec3};
use rayon::prelude::*;

use super::field_sampling::vertex_position;
use crate::field::ScalarField;
use crate::mesh::TriMesh;
use crate::mesh::correction::CrossedEdge;
use crate::neighbours::handler_array::HandlerArray;
use crate::neighbours::neighbourhood::Neighbourhood;
use crate::report::CorrectionFigures;

/// Cells per side of the middle level of narrowing.
const BLOCK: i32 = 4;

/// Moves every vertex of `mesh` strictly inside its grid edge onto the zero level of `field`
/// with `iterations` Newton steps; `bricks` are ranges of vertices that lie close together
/// (each within one brick), `handlers` the particles `field` samples.
pub fn correct_vertices<F: ScalarField + ?Sized>(
    mesh: &mut TriMesh,
    bricks: &[Range<usize>],
    cell: f32,
    handlers: &HandlerArray,
    field: &F,
    iterations: u32,
) -> CorrectionFigures {
    let reach = field.support();
    let own_reach = field.reach_channel();
    let vertices = &mesh.vertices;
    let per_brick: Vec<(usize, Vec<Moved>)> = bricks
        .par_iter()
        .map_init(
            || ([(); 3].map(|_| Neighbourhood::default()), Vec::new()),
            |([brick_near, block_near, cell_near], order), range| {
                order.clear();
                order.extend(
                    range
                        .clone()
                        .filter_map(|i| edge_of(vertices[i], cell).map(|(a, axis)| (a, axis, i))),
                );
                let Some((lo, hi)) = order.iter().map(|e| e.0).fold(None, |b, a| {
                    let (lo, hi) = b.unwrap_or((a, a));
                    Some((lo.min(a), hi.max(a)))
                }) else {
                    return (range.start, Vec::new());
                };
                let at = |c: IVec3| vertex_position(c, cell);
                brick_near.gather_box(handlers, at(lo), at(hi + 1), reach, own_reach);
                let block_of = |c: IVec3| c.div_euclid(IVec3::splat(BLOCK));
                order.sort_unstable_by_key(|&(a, axis, i)| {
                    let b = block_of(a);
                    (b.z, b.y, b.x, a.z, a.y, a.x, axis, i)
                });
                let mut out = Vec::with_capacity(order.len());
                for block in order.chunk_by(|a, b| block_of(a.0) == block_of(b.0)) {
                    let b = block_of(block[0].0) * BLOCK;
                    block_near.filter_box(brick_near, at(b), at(b + BLOCK), reach, own_reach);
                    for run in block.chunk_by(|a, b| a.0 == b.0) {
                        let (clo, chi) = (at(run[0].0), at(run[0].0 + 1));
                        cell_near.filter_box(block_near, clo, chi, reach, own_reach);
                        let near = &*cell_near;
                        let value = |x: Vec3| field.value(near, x - clo);
                        let eval = |x: Vec3| (value(x), field.gradient(near, x - clo));
                        for &(a, axis, i) in run {
                            let (pa, pb) = (at(a), at(a + IVec3::AXES[axis]));
                            let edge = CrossedEdge {
                                a: pa,
                                b: pb,
                                value_a: value(pa),
                                value_b: value(pb),
                            };
                            let p = vertices[i];
                            let t0 = (p[axis] - pa[axis]) / cell;
                            // Corners that no longer bracket the level (a value of about
                            // 0 evaluated in another order) leave the vertex where it is.
                            if (edge.value_a < 0.0) == (edge.value_b < 0.0) {
                                continue;
                            }
                            let mut before = None;
                            let t = edge.correct(0.0, iterations, |x| {
                                let (v, g) = eval(x);
                                before.get_or_insert(v);
                                (v, g)
                            });
                            let before = before.unwrap_or_else(|| value(p)).abs();
                            let moved = edge.at(t);
                            let after = value(moved).abs();
                            // A few steps across a kink of the field (SSP07's f(λ), an
                            // eigenvalue crossing) can end farther from the level than they
                            // began: the vertex then stays where it was.
                            out.push(if after < before {
                                Moved {
                                    vertex: i,
                                    position: moved,
                                    shift: (t - t0).abs(),
                                    before,
                                    after,
                                }
                            } else {
                                Moved {
                                    vertex: i,
                                    position: p,
                                    shift: 0.0,
                                    before,
                                    after: before,
                                }
                            });
                        }
                    }
                }
                (range.start, out)
            },
        )
        .collect();
    let mut figures = CorrectionFigures::default();
    let (mut shift, mut before, mut after) = (0.0f64, 0.0f64, 0.0f64);
    for m in per_brick.iter().flat_map(|(_, moved)| moved) {
        let v = &mut mesh.vertices[m.vertex];
        if *v != m.position {
            *v = m.position;
            figures.moved += 1;
        }
        figures.vertices += 1;
        shift += f64::from(m.shift);
        before += f64::from(m.before);
        after += f64::from(m.after);
        figures.shift_max = figures.shift_max.max(m.shift.into());
        figures.residual_before_max = figures.residual_before_max.max(m.before.into());
        figures.residual_after_max = figures.residual_after_max.max(m.after.into());
    }
    let n = figures.vertices.max(1) as f64;
    figures.shift_mean = shift / n;
    figures.residual_before_mean = before / n;
    figures.residual_after_mean = after / n;
    figures
}

/// A vertex's corrected position, and how far it moved and how close it came.
struct Moved {
    vertex: usize,
    position: Vec3,
    shift: f32,
    before: f32,
    after: f32,
}

/// The grid edge that vertex `p` lies strictly inside: its lower corner and its axis. None
/// for a vertex on a grid corner (a corner value of exactly 0), which is on the surface.
pub(crate) fn edge_of(p: Vec3, cell: f32) -> Option<(IVec3, usize)> {
    let mut corner = IVec3::ZERO;
    let mut free = None;
    for k in 0..3 {
        let on = |g: i32| vertex_position(IVec3::splat(g), cell).x;
        let mut g = (f64::from(p[k]) / f64::from(cell)).floor() as i32;
        // The division rounds: settle g so that on(g) ≤ p < on(g + 1).
        if on(g) > p[k] {
            g -= 1;
        } else if on(g + 1) <= p[k] {
            g += 1;
        }
        corner[k] = g;
        if on(g) != p[k] {
            if free.is_some() {
                return None;
            }
            free = Some(k);
        }
    }
    free.map(|axis| (corner, axis))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_vertex_gives_back_its_edge() {
        let cell = 0.007f32;
        for (corner, axis, t) in [
            (IVec3::new(3, -5, 120), 0, 0.3f32),
            (IVec3::new(-7, 0, 2), 1, 1e-6),
            (IVec3::new(1000, 999, -1001), 2, 0.999_99),
        ] {
            let mut p = vertex_position(corner, cell);
            p[axis] += t * cell;
            assert_eq!(edge_of(p, cell), Some((corner, axis)), "{p}");
        }
        assert_eq!(
            edge_of(vertex_position(IVec3::new(4, 5, 6), cell), cell),
            None
        );
    }
}
