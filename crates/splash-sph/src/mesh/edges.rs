//! A triangle mesh's distinct edges and each corner's edge: what Blender's meshes store beside
//! the triangles, handed over instead of being rebuilt there (`Mesh.update(calc_edges=True)`
//! took 35 ms in Blender 4.5 and 68 ms in 3.4 for 280 k triangles; this takes a few).

use crate::error::Result;

/// The undirected edges of a triangle mesh.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Edges {
    /// Each distinct edge once, its lower vertex first; in order of that vertex, then of the
    /// first corner that walks the edge.
    pub pairs: Vec<[u32; 2]>,
    /// For corner `3 f + k`, the index in `pairs` of the edge from its vertex to the next
    /// corner's (`k + 1`, wrapping), as Blender's loops point to their edges.
    pub corners: Vec<u32>,
}

impl Edges {
    /// The edges of `triangles` over `vertices` vertices: the corners counted and placed under
    /// the lower vertex of their edge, then each vertex's few numbered by their upper vertex.
    /// A triangle repeating a vertex gives the edge from it to itself. Fails when a triangle
    /// names a vertex beyond `vertices`.
    pub fn of(vertices: usize, triangles: &[[u32; 3]]) -> Result<Edges> {
        if let Some((f, t)) = triangles
            .iter()
            .enumerate()
            .find(|(_, t)| t.iter().any(|&v| v as usize >= vertices))
        {
            bail_input!("triangle {f} names vertex {t:?} of a mesh with {vertices} vertices");
        }
        if 3 * triangles.len() >= u32::MAX as usize {
            bail_limit!("{} triangles: at most 2^32 / 3", triangles.len());
        }
        let corners = 3 * triangles.len();
        // Each corner's side, lower vertex first.
        let sides = || {
            triangles.iter().flat_map(|t| {
                [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])].map(|(a, b)| (a.min(b), a.max(b)))
            })
        };
        let mut offsets = vec![0u32; vertices + 1];
        for (lo, _) in sides() {
            offsets[lo as usize + 1] += 1;
        }
        for v in 0..vertices {
            offsets[v + 1] += offsets[v];
        }
        // Under each lower vertex, the upper vertices and corners of its sides, in corner order.
        let (mut upper, mut corner) = (vec![0u32; corners], vec![0u32; corners]);
        let mut cursor = offsets.clone();
        for (c, (lo, hi)) in sides().enumerate() {
            let slot = &mut cursor[lo as usize];
            upper[*slot as usize] = hi;
            corner[*slot as usize] = c as u32;
            *slot += 1;
        }
        drop(cursor);
        let mut pairs = Vec::with_capacity(corners / 2 + 1);
        let mut of_corner = vec![0u32; corners];
        for (lo, row) in offsets.windows(2).enumerate() {
            let row = row[0] as usize..row[1] as usize;
            let (upper, corner) = (&upper[row.clone()], &corner[row]);
            for (i, (&hi, &c)) in upper.iter().zip(corner).enumerate() {
                // A vertex has a handful of sides: a scan beats a map.
                of_corner[c as usize] = match upper[..i].iter().position(|&h| h == hi) {
                    Some(j) => of_corner[corner[j] as usize],
                    None => {
                        pairs.push([lo as u32, hi]);
                        (pairs.len() - 1) as u32
                    }
                };
            }
        }
        Ok(Edges {
            pairs,
            corners: of_corner,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::TriMesh;
    use crate::mesh::topology::topology;
    use glam::Vec3;

    /// Each corner's edge joins its vertex and the next corner's, each pair is distinct and
    /// lower-first, and every pair is some corner's.
    fn check(vertices: usize, triangles: &[[u32; 3]], e: &Edges) {
        assert_eq!(e.corners.len(), 3 * triangles.len());
        for (c, &i) in e.corners.iter().enumerate() {
            let t = triangles[c / 3];
            let (a, b) = (t[c % 3], t[(c + 1) % 3]);
            assert_eq!(e.pairs[i as usize], [a.min(b), a.max(b)], "corner {c}");
        }
        let mut sorted = e.pairs.clone();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!(sorted.len(), e.pairs.len(), "an edge twice");
        assert!(
            e.pairs
                .iter()
                .all(|p| p[0] <= p[1] && (p[1] as usize) < vertices)
        );
        let mut used = vec![false; e.pairs.len()];
        e.corners.iter().for_each(|&i| used[i as usize] = true);
        assert!(used.iter().all(|&u| u), "an edge no corner walks");
    }

    #[test]
    fn a_closed_mesh_has_three_halves_of_its_triangles_as_edges_each_walked_twice() {
        let mut rng = 7u32;
        let mut next = move || {
            rng = rng.wrapping_mul(1664525).wrapping_add(1013904223);
            (rng >> 8) as f32 / (1 << 24) as f32
        };
        // A fan-triangulated sphere: rings of vertices, caps at the poles, shuffled indices.
        let (rings, around) = (9u32, 13u32);
        let mut triangles = Vec::new();
        let ring = |i: u32, j: u32| 2 + i * around + j % around;
        for j in 0..around {
            triangles.push([0, ring(0, j + 1), ring(0, j)]);
            triangles.push([1, ring(rings - 1, j), ring(rings - 1, j + 1)]);
            for i in 0..rings - 1 {
                let (a, b, c, d) = (
                    ring(i, j),
                    ring(i, j + 1),
                    ring(i + 1, j),
                    ring(i + 1, j + 1),
                );
                triangles.push([a, b, d]);
                triangles.push([a, d, c]);
            }
        }
        let n = (2 + rings * around) as usize;
        let mut relabel: Vec<u32> = (0..n as u32).collect();
        for i in (1..n).rev() {
            relabel.swap(i, (next() * (i + 1) as f32) as usize % (i + 1));
        }
        let triangles: Vec<[u32; 3]> = triangles
            .iter()
            .map(|t| t.map(|v| relabel[v as usize]))
            .collect();
        let e = Edges::of(n, &triangles).unwrap();
        check(n, &triangles, &e);
        let mesh = TriMesh {
            vertices: vec![Vec3::ZERO; n],
            normals: Vec::new(),
            triangles: triangles.clone(),
        };
        assert_eq!(e.pairs.len(), topology(&mesh).edges);
        assert_eq!(2 * e.pairs.len(), 3 * triangles.len());
        let mut walks = vec![0; e.pairs.len()];
        e.corners.iter().for_each(|&i| walks[i as usize] += 1);
        assert!(walks.iter().all(|&w| w == 2));
    }

    #[test]
    fn open_non_manifold_and_degenerate_triangles_and_bad_indices() {
        // Three triangles on one edge (0, 1), a lone one, one repeating a vertex.
        let triangles = [[0, 1, 2], [1, 0, 3], [0, 1, 4], [5, 6, 7], [2, 2, 3]];
        let e = Edges::of(8, &triangles).unwrap();
        check(8, &triangles, &e);
        assert_eq!(e.pairs[0], [0, 1]);
        assert_eq!(e.corners.iter().filter(|&&i| i == 0).count(), 3);
        assert!(e.pairs.contains(&[2, 2]));
        assert_eq!(Edges::of(0, &[]).unwrap(), Edges::default());
        let error = Edges::of(7, &triangles).unwrap_err().to_string();
        assert!(
            error.contains("triangle 3") && error.contains("7 vertices"),
            "{error}"
        );
    }
}
