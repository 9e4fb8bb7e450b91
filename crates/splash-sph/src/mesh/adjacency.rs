//! The triangles and neighbours around each vertex of a [`TriMesh`](super::TriMesh), as
//! compressed rows (CSR): the one-ring that smoothing, vertex normals and component labels read,
//! and the counting pass that the decimation's working stars share.

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
    /// The rows of `triangles` over `vertices` vertices (see `vertex_rows`).
    pub fn new(vertices: usize, triangles: &[[u32; 3]]) -> VertexFaces {
        assert!(
            3 * triangles.len() < u32::MAX as usize,
            "at most 2^32 / 3 triangles"
        );
        let mut offsets = Vec::new();
        let mut faces = Vec::new();
        let mut after = vec![0u32; 3 * triangles.len()];
        vertex_rows(
            &mut offsets,
            &mut faces,
            vertices,
            triangles,
            |_| true,
            |slot, t, k| after[slot] = triangles[t][(k + 1) % 3],
        );
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

/// The triangles around each vertex as rows: `offsets` gets `vertices + 1` row starts and
/// `faces`, row after row, the indices of the triangles that `keep` accepts, in increasing
/// order; `place(slot, triangle, corner)` sees where each corner went, for arrays that run
/// beside `faces`. Counting then placing, serially: two passes over the indices, no sort (a
/// few ms per million triangles); the arrays' allocations are reused.
pub(crate) fn vertex_rows(
    offsets: &mut Vec<u32>,
    faces: &mut Vec<u32>,
    vertices: usize,
    triangles: &[[u32; 3]],
    keep: impl Fn(&[u32; 3]) -> bool,
    mut place: impl FnMut(usize, usize, usize),
) {
    offsets.clear();
    offsets.resize(vertices + 1, 0);
    for t in triangles.iter().filter(|t| keep(t)) {
        for &v in t {
            offsets[v as usize + 1] += 1;
        }
    }
    for v in 0..vertices {
        offsets[v + 1] += offsets[v];
    }
    faces.clear();
    faces.resize(offsets[vertices] as usize, 0);
    // Fill from the front of each row, using `offsets[v]` as the cursor, then shift back.
    for (i, t) in triangles.iter().enumerate() {
        if !keep(t) {
            continue;
        }
        for (k, &v) in t.iter().enumerate() {
            let slot = &mut offsets[v as usize];
            faces[*slot as usize] = i as u32;
            place(*slot as usize, i, k);
            *slot += 1;
        }
    }
    offsets.copy_within(0..vertices, 1);
    offsets[0] = 0;
}
