//! The triangles and neighbours around each vertex of a [`TriMesh`](super::TriMesh), as
//! compressed rows (CSR): the one-ring that smoothing, vertex normals and component labels read.

/// For vertex `v`, `faces[offsets[v]..offsets[v + 1]]` are the triangles that use it, in
/// increasing order (so whatever reads them sums in the same order on any thread count), and
/// `next[offsets[v]..offsets[v + 1]]` the vertex that follows `v` in each of them: on a closed
/// oriented manifold every edge from `v` is walked away from `v` by exactly one triangle, so
/// these are `v`'s neighbours, each once.
#[derive(Debug, Clone, Default)]
pub struct VertexFaces {
    /// `vertices + 1` row starts.
    pub offsets: Vec<u32>,
    /// Triangle indices, row after row.
    pub faces: Vec<u32>,
    /// The vertex after the row's vertex in each of those triangles.
    pub next: Vec<u32>,
}

impl VertexFaces {
    /// The rows of `triangles` over `vertices` vertices. Counting then placing, serially: two
    /// passes over the indices, no sort (a few ms per million triangles).
    pub fn new(vertices: usize, triangles: &[[u32; 3]]) -> VertexFaces {
        assert!(
            3 * triangles.len() < u32::MAX as usize,
            "at most 2^32 / 3 triangles"
        );
        let mut offsets = vec![0u32; vertices + 1];
        for t in triangles {
            for &v in t {
                offsets[v as usize + 1] += 1;
            }
        }
        for v in 0..vertices {
            offsets[v + 1] += offsets[v];
        }
        let mut next = offsets.clone();
        let mut faces = vec![0u32; 3 * triangles.len()];
        let mut after = vec![0u32; 3 * triangles.len()];
        for (i, t) in triangles.iter().enumerate() {
            for k in 0..3 {
                let slot = &mut next[t[k] as usize];
                faces[*slot as usize] = i as u32;
                after[*slot as usize] = t[(k + 1) % 3];
                *slot += 1;
            }
        }
        VertexFaces {
            offsets,
            faces,
            next: after,
        }
    }

    /// The triangles around `v`.
    pub fn of(&self, v: usize) -> &[u32] {
        &self.faces[self.offsets[v] as usize..self.offsets[v + 1] as usize]
    }

    /// The neighbours of `v` (see the type's docs).
    pub fn neighbours(&self, v: usize) -> &[u32] {
        &self.next[self.offsets[v] as usize..self.offsets[v + 1] as usize]
    }
}
