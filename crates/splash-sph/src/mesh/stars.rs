//! Working stars (the triangles around each vertex, rebuilt as triangles die), the input checks
//! and the area-weighted vertex normals of decimation, clipping and component removal.

use super::TriMesh;
use super::adjacency::vertex_rows;
use crate::error::{Error, Result};
use glam::Vec3;
use rayon::prelude::*;

/// Triangle marked removed in a working triangle array: [`Stars::rebuild`] skips it.
pub(crate) const DEAD: u32 = u32::MAX;

/// The triangles around each vertex ("star"), in increasing triangle index.
#[derive(Default)]
pub(crate) struct Stars {
    offsets: Vec<u32>,
    triangles: Vec<u32>,
}

impl Stars {
    /// Recounts the stars of `vertices` vertices from the triangles whose first index is not
    /// [`DEAD`], reusing the arrays of the previous call.
    pub(crate) fn rebuild(&mut self, vertices: usize, triangles: &[[u32; 3]]) {
        vertex_rows(
            &mut self.offsets,
            &mut self.triangles,
            vertices,
            triangles,
            |t| t[0] != DEAD,
            |t, _| t as u32,
        );
    }

    /// The triangles around `v`.
    pub(crate) fn of(&self, v: u32) -> &[u32] {
        let v = v as usize;
        &self.triangles[self.offsets[v] as usize..self.offsets[v + 1] as usize]
    }
}

/// Refuses a mesh whose triangles reference a missing vertex, whose normals are neither absent
/// nor one per vertex, or too large for the `u32` corner indices of the post-processing.
pub(crate) fn validate(mesh: &TriMesh) -> Result<()> {
    let n = mesh.vertices.len();
    if !mesh.normals.is_empty() && mesh.normals.len() != n {
        return Err(Error::Input(format!(
            "mesh has {} normals for {n} vertices",
            mesh.normals.len()
        )));
    }
    if mesh.triangles.len() >= (u32::MAX / 3) as usize || n >= u32::MAX as usize {
        return Err(Error::Limit(format!(
            "mesh of {} triangles and {n} vertices is too large to post-process",
            mesh.triangles.len()
        )));
    }
    if let Some((i, t)) = mesh
        .triangles
        .iter()
        .enumerate()
        .find(|(_, t)| t.iter().any(|&v| v as usize >= n))
    {
        return Err(Error::Input(format!(
            "triangle {i} references vertex {}, mesh has {n} vertices",
            t.iter().max().unwrap()
        )));
    }
    if let Some(i) = mesh.vertices.iter().position(|v| !v.is_finite()) {
        return Err(Error::Input(format!("vertex {i} is not finite")));
    }
    Ok(())
}

/// The normal of triangle `t` of `vertices`, (b − a) × (c − a): counter-clockwise seen from
/// outside, its length twice the triangle's area.
#[inline]
pub(crate) fn area_normal(t: &[u32; 3], vertices: &[Vec3]) -> Vec3 {
    let [a, b, c] = t.map(|i| vertices[i as usize]);
    (b - a).cross(c - a)
}

/// The unit normal of triangle `t` of `vertices`, zero if it is degenerate.
#[inline]
pub(crate) fn unit_normal(t: &[u32; 3], vertices: &[Vec3]) -> Vec3 {
    area_normal(t, vertices).normalize_or_zero()
}

/// Unit normals from the area-weighted sum of the face normals around each vertex; zero for a
/// vertex without a triangle of non-zero area.
pub(crate) fn area_weighted_normals(vertices: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
    // The faces' normals in parallel, their sums in triangle order (the same bits on any
    // number of threads); a face normal's length is twice the area, so the weighting comes
    // for free.
    let faces: Vec<Vec3> = triangles
        .par_iter()
        .map(|t| area_normal(t, vertices))
        .collect();
    let mut sums = vec![Vec3::ZERO; vertices.len()];
    for (t, &n) in triangles.iter().zip(&faces) {
        for &v in t {
            sums[v as usize] += n;
        }
    }
    sums.par_iter_mut().for_each(|n| *n = n.normalize_or_zero());
    sums
}

/// Keeps the vertices that `triangles` reference, in their order, with their normals when
/// `normals` is not empty, and renumbers the triangles.
pub(crate) fn compact(vertices: &[Vec3], normals: &[Vec3], triangles: &[[u32; 3]]) -> TriMesh {
    let mut new_index = vec![u32::MAX; vertices.len()];
    for t in triangles {
        for &v in t {
            new_index[v as usize] = 0;
        }
    }
    let mut kept = Vec::new();
    let mut kept_normals = Vec::new();
    for (old, slot) in new_index.iter_mut().enumerate() {
        if *slot == 0 {
            *slot = kept.len() as u32;
            kept.push(vertices[old]);
            if !normals.is_empty() {
                kept_normals.push(normals[old]);
            }
        }
    }
    TriMesh {
        vertices: kept,
        normals: kept_normals,
        triangles: triangles
            .iter()
            .map(|t| t.map(|v| new_index[v as usize]))
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stars_skip_dead_triangles_and_keep_order() {
        let triangles = [[0, 1, 2], [DEAD, 0, 0], [2, 1, 3], [0, 2, 3]];
        let mut stars = Stars::default();
        stars.rebuild(5, &triangles);
        assert_eq!(stars.of(0), &[0, 3]);
        assert_eq!(stars.of(1), &[0, 2]);
        assert_eq!(stars.of(2), &[0, 2, 3]);
        assert_eq!(stars.of(3), &[2, 3]);
        assert!(stars.of(4).is_empty());
    }

    #[test]
    fn validate_names_the_bad_index() {
        let mesh = TriMesh {
            vertices: vec![Vec3::ZERO; 3],
            normals: vec![],
            triangles: vec![[0, 1, 2], [0, 1, 7]],
        };
        let message = validate(&mesh).unwrap_err().to_string();
        assert_eq!(
            message,
            "triangle 1 references vertex 7, mesh has 3 vertices"
        );
    }
}
