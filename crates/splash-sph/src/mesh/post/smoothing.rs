//! Taubin's λ|μ smoothing (Taubin 1995, "A signal processing approach to fair surface design"):
//! umbrella-operator Laplacian steps alternating a shrinking λ > 0 and an inflating μ < −λ, a
//! low-pass filter that removes Marching Cubes' ripples and stretched triangles without the
//! shrinkage of plain Laplacian smoothing; tangential relaxation, which evens out the
//! triangles without moving the surface; and area-weighted vertex normals.

use glam::Vec3;
use rayon::prelude::*;

use crate::mesh::adjacency::{Neighbours, VertexFaces};
use crate::mesh::area_normal;

/// Vertices per parallel task: large enough to amortise the task, small enough to balance.
const CHUNK: usize = 4096;

/// `iterations` λ|μ pairs over `vertices` (Jacobi updates: every vertex reads the previous
/// positions, so the result does not depend on the thread count). `scratch` must have the
/// length of `vertices`; it holds garbage afterwards.
pub fn taubin(
    vertices: &mut [Vec3],
    scratch: &mut [Vec3],
    rings: &Neighbours,
    iterations: u32,
    lambda: f32,
    mu: f32,
) {
    debug_assert_eq!(vertices.len(), scratch.len());
    for _ in 0..iterations {
        umbrella_step(vertices, scratch, rings, lambda);
        umbrella_step(scratch, vertices, rings, mu);
    }
}

/// The umbrella operator: the mean of `v`'s neighbours minus `v`.
#[inline]
fn umbrella(from: &[Vec3], rings: &Neighbours, v: usize) -> Vec3 {
    let ring = rings.of(v);
    let n = ring.len();
    if n == 0 {
        return Vec3::ZERO;
    }
    let sum: Vec3 = ring.iter().map(|&u| from[u as usize]).sum();
    sum / n as f32 - from[v]
}

/// `to[v] = from[v] + factor · umbrella(v)`.
fn umbrella_step(from: &[Vec3], to: &mut [Vec3], rings: &Neighbours, factor: f32) {
    to.par_chunks_mut(CHUNK).enumerate().for_each(|(c, out)| {
        for (k, slot) in out.iter_mut().enumerate() {
            let v = c * CHUNK + k;
            *slot = from[v] + factor * umbrella(from, rings, v);
        }
    });
}

/// Unit area-weighted vertex normals (the sum of the cross products of the triangles around
/// each vertex) into `normals`; a vertex without area keeps a zero normal.
pub fn vertex_normals(
    vertices: &[Vec3],
    triangles: &[[u32; 3]],
    rings: &VertexFaces,
    normals: &mut [Vec3],
) {
    normals
        .par_chunks_mut(CHUNK)
        .enumerate()
        .for_each(|(c, out)| {
            for (k, n) in out.iter_mut().enumerate() {
                let mut sum = Vec3::ZERO;
                for f in rings.of(c * CHUNK + k) {
                    sum += area_normal(&triangles[f], vertices);
                }
                *n = sum.normalize_or_zero();
            }
        });
}

/// `iterations` umbrella steps with the normal part of each move taken out: vertices slide
/// along the surface toward the centre of their ring, which evens out stretched and squeezed
/// triangles without moving the surface (to first order). `normals` are unit vertex normals.
/// The steps go back and forth between `vertices` and `scratch` (Jacobi updates, as
/// [`taubin`]); an odd count copies the last step back.
pub fn relax_tangentially(
    vertices: &mut [Vec3],
    scratch: &mut [Vec3],
    normals: &[Vec3],
    rings: &Neighbours,
    iterations: u32,
    factor: f32,
) {
    debug_assert_eq!(vertices.len(), scratch.len());
    for _ in 0..iterations / 2 {
        relax_step(vertices, scratch, normals, rings, factor);
        relax_step(scratch, vertices, normals, rings, factor);
    }
    if iterations % 2 == 1 {
        relax_step(vertices, scratch, normals, rings, factor);
        vertices
            .par_chunks_mut(CHUNK)
            .zip(scratch.par_chunks(CHUNK))
            .for_each(|(to, from)| to.copy_from_slice(from));
    }
}

/// One step of [`relax_tangentially`] from `from` into `to`.
fn relax_step(from: &[Vec3], to: &mut [Vec3], normals: &[Vec3], rings: &Neighbours, factor: f32) {
    to.par_chunks_mut(CHUNK).enumerate().for_each(|(c, out)| {
        for (k, slot) in out.iter_mut().enumerate() {
            let v = c * CHUNK + k;
            let (step, n) = (umbrella(from, rings, v), normals[v]);
            *slot = from[v] + factor * (step - step.dot(n) * n);
        }
    });
}
