//! The mesh of the crossed cells: Marching Cubes triangles from the project's tables, one vertex
//! per crossed edge shared by its cells, each corrected onto the isosurface (Sec. III-D2) with
//! `CrossedEdge::correct`, then trimmed (Sec. III-D3) and given SPH-gradient normals (Sec.
//! III-D4).

use glam::{IVec3, Vec3};
use rayon::prelude::*;
use rustc_hash::FxHashMap;

use super::sph_interpolant::Interpolant;
use super::stats::CorrectionStats;
use super::surface_following::CrossedCell;
use super::trimming::{Trimmed, trim};
use super::virtual_grid::VirtualGrid;
use crate::mesh::correction::CrossedEdge;
use crate::mesh::marching_cubes::{cases, corner_offset, edge_axis, edge_corners};

/// The untrimmed Marching Cubes mesh: one crossed edge per vertex, triangles wound
/// counter-clockwise seen from where A is above the level.
pub(crate) struct Triangulated {
    pub edges: Vec<CrossedEdge>,
    pub triangles: Vec<[u32; 3]>,
}

fn node_of(cell: IVec3, c: usize) -> IVec3 {
    let [x, y, z] = corner_offset(c);
    cell + IVec3::new(x as i32, y as i32, z as i32)
}

/// Triangulates `cells` (in lexicographic order, so vertex numbers do not depend on threads).
pub(crate) fn triangulate(cells: &[CrossedCell], grid: &VirtualGrid) -> Triangulated {
    let mut index: FxHashMap<(IVec3, u8), u32> = FxHashMap::default();
    let (mut edges, mut triangles) = (Vec::new(), Vec::new());
    for cc in cells {
        for tri in cases()[cc.case()].triangles() {
            triangles.push(tri.map(|e| {
                let (c0, c1) = edge_corners(e as usize);
                let (n0, axis) = (node_of(cc.cell, c0), edge_axis(e as usize) as u8);
                *index.entry((n0, axis)).or_insert_with(|| {
                    edges.push(CrossedEdge {
                        a: grid.node(n0),
                        b: grid.node(node_of(cc.cell, c1)),
                        value_a: cc.values[c0] as f32,
                        value_b: cc.values[c1] as f32,
                    });
                    edges.len() as u32 - 1
                })
            }));
        }
    }
    Triangulated { edges, triangles }
}

/// The vertices on the isosurface: each edge's crossing after `iterations` Newton steps on
/// A − `level`, and the corrections' sizes.
pub(crate) fn place(
    it: &Interpolant,
    edges: &[CrossedEdge],
    level: f64,
    iterations: u32,
) -> (Vec<Vec3>, CorrectionStats) {
    let channel = it.channels.value;
    let placed: Vec<(Vec3, f32)> = edges
        .par_iter()
        .map(|edge| {
            let t0 = edge.linear_t(0.0);
            let t = edge.correct(0.0, iterations, |x| {
                let s = it.sample(x, channel);
                ((s.value - level) as f32, s.gradient.as_vec3())
            });
            (edge.at(t), (t - t0).abs())
        })
        .collect();
    let edge_length = edges.first().map_or(0.0, |e| (e.b - e.a).length());
    let stats = CorrectionStats::of(placed.iter().map(|p| p.1), edge_length);
    (placed.into_iter().map(|p| p.0).collect(), stats)
}

/// A point of a trimming cut moved onto the isosurface by Newton steps along ∇A.
fn project(it: &Interpolant, mut x: Vec3, level: f64, iterations: u32) -> Vec3 {
    for _ in 0..iterations {
        let s = it.sample(x, it.channels.value);
        let g2 = s.gradient.length_squared();
        if g2.is_nan() || g2 <= 0.0 || s.value == level {
            break;
        }
        x -= (s.gradient * ((s.value - level) / g2)).as_vec3();
    }
    x
}

/// The finished mesh's arrays.
pub(crate) struct Finished {
    pub vertices: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    pub trim_cases: [usize; 5],
}

/// Trims the mesh at `vertex_threshold`, adds the cut vertices (projected onto the isosurface
/// with `iterations` steps), drops vertices no triangle uses, and samples normals.
pub(crate) fn finish(
    it: &Interpolant,
    mut vertices: Vec<Vec3>,
    triangles: &[[u32; 3]],
    level: f64,
    iterations: u32,
    vertex_threshold: f64,
) -> Finished {
    let weights: Vec<f64> = vertices
        .par_iter()
        .map(|&x| it.sample(x, it.channels.value).weight)
        .collect();
    let Trimmed {
        triangles,
        cuts,
        cases,
    } = trim(&weights, triangles, vertex_threshold, vertices.len() as u32);
    let cut_points: Vec<Vec3> = cuts
        .par_iter()
        .map(|&(a, b, t)| {
            let x = vertices[a as usize].lerp(vertices[b as usize], t as f32);
            project(it, x, level, iterations)
        })
        .collect();
    vertices.extend(cut_points);
    // Renumber the vertices the triangles use, in their old order.
    let mut new_index = vec![u32::MAX; vertices.len()];
    for &v in triangles.iter().flatten() {
        new_index[v as usize] = 0;
    }
    let mut kept = Vec::with_capacity(vertices.len());
    for (i, n) in new_index.iter_mut().enumerate() {
        if *n == 0 {
            *n = kept.len() as u32;
            kept.push(vertices[i]);
        }
    }
    let triangles = triangles
        .iter()
        .map(|t| t.map(|v| new_index[v as usize]))
        .collect();
    let normals = kept
        .par_iter()
        .map(|&x| {
            let g = it.sample(x, it.channels.value).gradient.as_vec3();
            g.try_normalize().unwrap_or(Vec3::Z)
        })
        .collect();
    Finished {
        vertices: kept,
        normals,
        triangles,
        trim_cases: cases,
    }
}
