//! The triangles and neighbours around each vertex of a [`TriMesh`](super::TriMesh), as
//! compressed rows (CSR): the one-ring that smoothing, vertex normals and component labels read,
//! and the counting pass that the decimation's working stars share.

use rayon::prelude::*;

/// For vertex `v`, `corners[offsets[v]..offsets[v + 1]]` are its corners `3 f + k` (vertex
/// `v` is corner `k` of triangle `f`), in increasing order (so whatever reads them sums in the
/// same order on any thread count). [`Neighbours`] keeps, beside them, the vertex that follows
/// `v` in each triangle: on a closed oriented manifold every edge from `v` is walked away from
/// `v` by exactly one triangle, so these are `v`'s neighbours, each once.
#[derive(Debug, Clone, Default)]
pub struct VertexFaces {
    /// `vertices + 1` row starts.
    pub offsets: Vec<u32>,
    /// Corners `3 f + k`, row after row.
    pub corners: Vec<u32>,
}

impl VertexFaces {
    /// The rows of `triangles` over `vertices` vertices (see `vertex_rows`).
    pub fn new(vertices: usize, triangles: &[[u32; 3]]) -> VertexFaces {
        assert!(
            3 * triangles.len() < u32::MAX as usize,
            "at most 2^32 / 3 triangles"
        );
        let mut offsets = Vec::new();
        let mut corners = Vec::new();
        vertex_rows(
            &mut offsets,
            &mut corners,
            vertices,
            triangles,
            |_| true,
            |t, k| (3 * t + k) as u32,
        );
        VertexFaces { offsets, corners }
    }

    /// The corners of `v`.
    #[inline]
    pub(crate) fn row(&self, v: usize) -> &[u32] {
        &self.corners[self.offsets[v] as usize..self.offsets[v + 1] as usize]
    }

    /// The triangles around `v`, in increasing order.
    #[inline]
    pub fn of(&self, v: usize) -> impl ExactSizeIterator<Item = usize> + '_ {
        self.row(v).iter().map(|&c| c as usize / 3)
    }
}

/// Each vertex's neighbours as rows beside its [`VertexFaces`] (the same row starts): the vertex
/// after it in each of its triangles, in the order of its corners (so each neighbour once on a
/// closed oriented manifold). Smoothing reads the rings dozens of times a mesh: stored, a step
/// reads one array instead of corners and then triangles, a third faster for 4 bytes a corner.
#[derive(Debug, Clone, Default)]
pub struct Neighbours {
    faces: VertexFaces,
    next: Vec<u32>,
}

impl Neighbours {
    /// The neighbours of `faces`, the rows of `triangles`, kept beside them.
    pub fn new(faces: VertexFaces, triangles: &[[u32; 3]]) -> Neighbours {
        let indices = triangles.as_flattened();
        let next = faces
            .corners
            .par_iter()
            .with_min_len(1 << 14)
            .map(|&c| indices[next_corner(c) as usize])
            .collect();
        Neighbours { faces, next }
    }

    /// The triangles' rows.
    pub fn faces(&self) -> &VertexFaces {
        &self.faces
    }

    /// The triangles' rows, the neighbours freed.
    pub fn into_faces(self) -> VertexFaces {
        self.faces
    }

    /// The number of vertices.
    pub fn vertices(&self) -> usize {
        self.faces.offsets.len().saturating_sub(1)
    }

    /// The neighbours of `v`.
    #[inline]
    pub fn of(&self, v: usize) -> &[u32] {
        let offsets = &self.faces.offsets;
        &self.next[offsets[v] as usize..offsets[v + 1] as usize]
    }
}

/// The corner after corner `c` of the same triangle.
#[inline]
pub(crate) fn next_corner(c: u32) -> u32 {
    if c % 3 == 2 { c - 2 } else { c + 1 }
}

/// The triangles around each vertex as rows: `offsets` gets `vertices + 1` row starts and
/// `faces`, row after row, `entry(triangle, corner)` for the corners of the triangles that
/// `keep` accepts, in increasing order of triangle. Counting then placing, serially: two passes over the indices, no sort (a
/// few ms per million triangles); the arrays' allocations are reused.
pub(crate) fn vertex_rows(
    offsets: &mut Vec<u32>,
    faces: &mut Vec<u32>,
    vertices: usize,
    triangles: &[[u32; 3]],
    keep: impl Fn(&[u32; 3]) -> bool,
    entry: impl Fn(usize, usize) -> u32,
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
    let len = offsets[vertices] as usize;
    if faces.capacity() < len {
        // Zeroed pages for a new array, rather than a fill before the placing writes them.
        *faces = vec![0; len];
    } else {
        faces.clear();
        faces.resize(len, 0);
    }
    // Fill from the front of each row, using `offsets[v]` as the cursor, then shift back.
    for (i, t) in triangles.iter().enumerate() {
        if !keep(t) {
            continue;
        }
        for (k, &v) in t.iter().enumerate() {
            let slot = &mut offsets[v as usize];
            faces[*slot as usize] = entry(i, k);
            *slot += 1;
        }
    }
    offsets.copy_within(0..vertices, 1);
    offsets[0] = 0;
}
