//! Exact topological checks of a [`TriMesh`]: edge manifoldness, orientation consistency,
//! connected components, Euler characteristic, enclosed volume and normal orientation.

use super::TriMesh;
use rayon::prelude::*;

/// Counts describing the combinatorial structure of a mesh: edge manifoldness, orientation
/// consistency, connected components and Euler characteristic.
///
/// Everything except `triangles`, `degenerate_triangles` and `unused_vertices` is computed on
/// the non-degenerate triangles only. Degenerate triangles (repeating a vertex index) are
/// counted in [`Topology::degenerate_triangles`] and otherwise ignored: they enclose nothing and
/// their "edges" (a vertex to itself, or one edge twice) would only blur the manifold checks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Topology {
    /// Length of the vertex array.
    pub vertices: usize,
    /// Length of the triangle array, degenerate ones included.
    pub triangles: usize,
    /// Distinct undirected edges.
    pub edges: usize,
    /// Edges used by exactly one triangle.
    pub boundary_edges: usize,
    /// Edges used by three or more triangles.
    pub non_manifold_edges: usize,
    /// Edges used by exactly two triangles that traverse it in the same direction, i.e. whose
    /// windings disagree.
    pub inconsistent_edges: usize,
    /// Triangles repeating a vertex index.
    pub degenerate_triangles: usize,
    /// Connected components, with vertex connectivity: triangles sharing only a vertex belong to
    /// the same component (two balls touching at a single vertex are one component).
    pub components: usize,
    /// Vertices that no triangle references (a reference from a degenerate triangle counts).
    pub unused_vertices: usize,
    /// `V - E + F` with `V` the vertices referenced by non-degenerate triangles and `F` the
    /// non-degenerate triangles: 2 per closed sphere-like component, 0 per torus.
    pub euler_characteristic: i64,
}

impl Topology {
    /// No boundary, no non-manifold and no inconsistently oriented edge: every edge is shared by
    /// exactly two triangles winding the same way.
    pub fn is_closed_manifold(&self) -> bool {
        self.boundary_edges == 0 && self.non_manifold_edges == 0 && self.inconsistent_edges == 0
    }
}

fn is_degenerate(t: &[u32; 3]) -> bool {
    t[0] == t[1] || t[1] == t[2] || t[0] == t[2]
}

/// Panics on a vertex index out of range: that is a bug in whatever built the mesh, not a
/// topological property to count.
fn check_indices(mesh: &TriMesh) {
    let n = mesh.vertices.len();
    let max = mesh
        .triangles
        .par_iter()
        .map(|t| t[0].max(t[1]).max(t[2]))
        .max();
    if let Some(max) = max {
        assert!(
            (max as usize) < n,
            "triangle references vertex {max}, mesh has {n} vertices"
        );
    }
}

/// Counts the topology of `mesh`. Sorts one packed `u64` per directed edge (rayon), so meshes of
/// millions of triangles take a fraction of a second.
pub fn topology(mesh: &TriMesh) -> Topology {
    check_indices(mesh);
    // Key = min << 33 | max << 1 | direction, so edges group by (min, max) after sorting and the
    // low bit says which way the triangle walks the edge. Needs indices below 2^31, which also
    // keeps every key below u64::MAX, the mark for a degenerate triangle's slots.
    assert!(
        mesh.vertices.len() <= 1 << 31,
        "topology supports at most 2^31 vertices"
    );
    let mut keys = vec![0u64; 3 * mesh.triangles.len()];
    keys.par_chunks_mut(3)
        .zip(&mesh.triangles)
        .for_each(|(slots, t)| {
            if is_degenerate(t) {
                slots.fill(u64::MAX);
                return;
            }
            for (slot, (a, b)) in slots
                .iter_mut()
                .zip([(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            {
                let (lo, hi, dir) = if a < b { (a, b, 0) } else { (b, a, 1) };
                *slot = (u64::from(lo) << 33) | (u64::from(hi) << 1) | dir;
            }
        });
    keys.par_sort_unstable();
    let degenerate = mesh
        .triangles
        .par_iter()
        .filter(|t| is_degenerate(t))
        .count();
    keys.truncate(keys.len() - 3 * degenerate);

    let (mut edges, mut boundary, mut non_manifold, mut inconsistent) = (0, 0, 0, 0);
    for group in keys.chunk_by(|a, b| a >> 1 == b >> 1) {
        edges += 1;
        match group {
            [_] => boundary += 1,
            [a, b] => inconsistent += usize::from(a == b),
            _ => non_manifold += 1,
        }
    }

    let faces = keys.len() / 3;

    let mut referenced = vec![false; mesh.vertices.len()];
    for t in &mesh.triangles {
        for &v in t {
            referenced[v as usize] = true;
        }
    }
    let unused = referenced.iter().filter(|&&r| !r).count();

    let mut uf = UnionFind::new(mesh.vertices.len());
    let mut used = vec![false; mesh.vertices.len()];
    for t in mesh.triangles.iter().filter(|t| !is_degenerate(t)) {
        uf.union(t[0], t[1]);
        uf.union(t[0], t[2]);
        for &v in t {
            used[v as usize] = true;
        }
    }
    let used_count = used.iter().filter(|&&u| u).count();
    let components = (0..mesh.vertices.len() as u32)
        .filter(|&v| used[v as usize] && uf.find(v) == v)
        .count();

    Topology {
        vertices: mesh.vertices.len(),
        triangles: mesh.triangles.len(),
        edges,
        boundary_edges: boundary,
        non_manifold_edges: non_manifold,
        inconsistent_edges: inconsistent,
        degenerate_triangles: degenerate,
        components,
        unused_vertices: unused,
        euler_characteristic: used_count as i64 - edges as i64 + faces as i64,
    }
}

fn triangle_volume(mesh: &TriMesh, t: &[u32; 3]) -> f64 {
    let [a, b, c] = t.map(|i| mesh.vertices[i as usize].as_dvec3());
    a.dot(b.cross(c)) / 6.0
}

/// Signed volume enclosed by the mesh (divergence theorem: the sum over triangles of
/// `det(a, b, c) / 6`), accumulated in `f64`. Positive for a closed mesh whose triangles wind
/// counter-clockwise seen from outside. For an open mesh the value depends on the origin.
pub fn signed_volume(mesh: &TriMesh) -> f64 {
    check_indices(mesh);
    // Fixed chunks summed in order: the same mesh gives the same bits whatever the threads.
    let partial: Vec<f64> = mesh
        .triangles
        .par_chunks(1 << 14)
        .map(|chunk| chunk.iter().map(|t| triangle_volume(mesh, t)).sum())
        .collect();
    partial.iter().sum()
}

/// `(triangle count, signed volume)` per connected component (vertex connectivity, as in
/// [`Topology::components`]), in order of each component's first triangle. Degenerate triangles
/// are left out of the counts.
pub fn component_volumes(mesh: &TriMesh) -> Vec<(usize, f64)> {
    check_indices(mesh);
    let mut uf = UnionFind::new(mesh.vertices.len());
    for t in mesh.triangles.iter().filter(|t| !is_degenerate(t)) {
        uf.union(t[0], t[1]);
        uf.union(t[0], t[2]);
    }
    // Root vertex -> index into the result, assigned on first sight.
    let mut slot = vec![u32::MAX; mesh.vertices.len()];
    let mut out: Vec<(usize, f64)> = Vec::new();
    for t in mesh.triangles.iter().filter(|t| !is_degenerate(t)) {
        let root = uf.find(t[0]) as usize;
        if slot[root] == u32::MAX {
            slot[root] = out.len() as u32;
            out.push((0, 0.0));
        }
        let entry = &mut out[slot[root] as usize];
        entry.0 += 1;
        entry.1 += triangle_volume(mesh, t);
    }
    out
}

/// Fraction of the vertices used by a non-degenerate triangle whose stored normal has a positive
/// dot product with the area-weighted sum of the face normals around it. 1.0 means the normals
/// point outward consistently with the winding; a vertex without a stored normal counts as
/// disagreeing. NaN when no vertex is used, so that any threshold check on it fails. (The
/// tests' check of the engines' normals.)
#[cfg(test)]
pub(crate) fn normal_agreement(mesh: &TriMesh) -> f64 {
    check_indices(mesh);
    let mut face_sum = vec![glam::Vec3::ZERO; mesh.vertices.len()];
    let mut used = vec![false; mesh.vertices.len()];
    for t in mesh.triangles.iter().filter(|t| !is_degenerate(t)) {
        // The cross product's length is twice the area: an area weighting for free.
        let n = super::area_normal(t, &mesh.vertices);
        for &v in t {
            face_sum[v as usize] += n;
            used[v as usize] = true;
        }
    }
    let (mut judged, mut agree) = (0usize, 0usize);
    for (v, sum) in face_sum.iter().enumerate() {
        if !used[v] {
            continue;
        }
        judged += 1;
        if mesh.normals.get(v).is_some_and(|n| n.dot(*sum) > 0.0) {
            agree += 1;
        }
    }
    if judged == 0 {
        f64::NAN
    } else {
        agree as f64 / judged as f64
    }
}

/// Disjoint sets over vertex indices, with path halving and union by size.
pub(super) struct UnionFind {
    parent: Vec<u32>,
    size: Vec<u32>,
}

impl UnionFind {
    pub(super) fn new(n: usize) -> Self {
        Self {
            parent: (0..n as u32).collect(),
            size: vec![1; n],
        }
    }

    pub(super) fn find(&mut self, mut v: u32) -> u32 {
        while self.parent[v as usize] != v {
            let grandparent = self.parent[self.parent[v as usize] as usize];
            self.parent[v as usize] = grandparent;
            v = grandparent;
        }
        v
    }

    pub(super) fn union(&mut self, a: u32, b: u32) {
        let (mut a, mut b) = (self.find(a), self.find(b));
        if a == b {
            return;
        }
        if self.size[a as usize] < self.size[b as usize] {
            std::mem::swap(&mut a, &mut b);
        }
        self.parent[b as usize] = a;
        self.size[a as usize] += self.size[b as usize];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tests::common::{merged, torus};
    use glam::Vec3;

    /// Builds a mesh whose normals point away from `center` (outward for convex shapes).
    fn mesh(vertices: Vec<Vec3>, triangles: Vec<[u32; 3]>, center: Vec3) -> TriMesh {
        let normals = vertices
            .iter()
            .map(|&v| (v - center).normalize_or_zero())
            .collect();
        TriMesh {
            vertices,
            normals,
            triangles,
        }
    }

    /// Unit cube [0,1]^3, 12 triangles counter-clockwise seen from outside.
    fn cube() -> TriMesh {
        let vertices = (0..8)
            .map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32))
            .collect();
        let triangles = vec![
            [0, 2, 3],
            [0, 3, 1], // z = 0
            [4, 5, 7],
            [4, 7, 6], // z = 1
            [0, 1, 5],
            [0, 5, 4], // y = 0
            [2, 6, 7],
            [2, 7, 3], // y = 1
            [0, 4, 6],
            [0, 6, 2], // x = 0
            [1, 3, 7],
            [1, 7, 5], // x = 1
        ];
        mesh(vertices, triangles, Vec3::splat(0.5))
    }

    fn tetrahedron(offset: Vec3) -> TriMesh {
        let vertices = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z]
            .map(|v| v + offset)
            .to_vec();
        let triangles = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        mesh(vertices, triangles, offset + Vec3::splat(0.25))
    }

    #[test]
    fn cube_is_closed_sphere() {
        let m = cube();
        let t = topology(&m);
        assert_eq!(
            t,
            Topology {
                vertices: 8,
                triangles: 12,
                edges: 18,
                boundary_edges: 0,
                non_manifold_edges: 0,
                inconsistent_edges: 0,
                degenerate_triangles: 0,
                components: 1,
                unused_vertices: 0,
                euler_characteristic: 2,
            }
        );
        assert!(t.is_closed_manifold());
        assert!((signed_volume(&m) - 1.0).abs() < 1e-12);
        assert_eq!(normal_agreement(&m), 1.0);
        let comps = component_volumes(&m);
        assert_eq!(comps.len(), 1);
        assert_eq!(comps[0].0, 12);
        assert!((comps[0].1 - 1.0).abs() < 1e-12);
    }

    #[test]
    fn inverted_cube_has_negative_volume_and_disagreeing_normals() {
        let mut m = cube();
        for t in &mut m.triangles {
            t.swap(1, 2);
        }
        assert!(topology(&m).is_closed_manifold());
        assert!((signed_volume(&m) + 1.0).abs() < 1e-12);
        assert_eq!(normal_agreement(&m), 0.0);
    }

    #[test]
    fn cube_with_hole() {
        let mut m = cube();
        m.triangles.remove(5);
        let t = topology(&m);
        assert_eq!(t.edges, 18);
        assert_eq!(t.boundary_edges, 3);
        assert_eq!(t.non_manifold_edges, 0);
        assert_eq!(t.inconsistent_edges, 0);
        assert_eq!(t.euler_characteristic, 8 - 18 + 11);
        assert!(!t.is_closed_manifold());
    }

    #[test]
    fn cube_with_flipped_triangle() {
        let mut m = cube();
        m.triangles[7].swap(0, 1);
        let t = topology(&m);
        assert_eq!(t.boundary_edges, 0);
        assert_eq!(t.non_manifold_edges, 0);
        assert_eq!(t.inconsistent_edges, 3);
        assert_eq!(t.euler_characteristic, 2);
        assert!(!t.is_closed_manifold());
    }

    #[test]
    fn book_of_three_pages_is_non_manifold() {
        let vertices = vec![
            Vec3::ZERO,
            Vec3::Z,
            Vec3::X,
            Vec3::Y,
            Vec3::new(-1.0, -1.0, 0.0),
        ];
        let m = mesh(vertices, vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]], Vec3::ZERO);
        let t = topology(&m);
        assert_eq!(t.edges, 7);
        assert_eq!(t.non_manifold_edges, 1);
        assert_eq!(t.boundary_edges, 6);
        assert_eq!(t.inconsistent_edges, 0);
        assert_eq!(t.components, 1);
        assert_eq!(t.euler_characteristic, 5 - 7 + 3);
        assert!(!t.is_closed_manifold());
    }

    #[test]
    fn two_tetrahedra() {
        let m = merged(&tetrahedron(Vec3::ZERO), &tetrahedron(Vec3::splat(3.0)));
        let t = topology(&m);
        assert_eq!(t.components, 2);
        assert_eq!(t.edges, 12);
        assert_eq!(t.euler_characteristic, 4);
        assert!(t.is_closed_manifold());
        let comps = component_volumes(&m);
        assert_eq!(comps.len(), 2);
        for (count, volume) in comps {
            assert_eq!(count, 4);
            assert!((volume - 1.0 / 6.0).abs() < 1e-9, "{volume}");
        }
        assert!((signed_volume(&m) - 2.0 / 6.0).abs() < 1e-9);
        assert_eq!(normal_agreement(&m), 1.0);
    }

    #[test]
    fn shared_vertex_joins_components() {
        // Second tetrahedron's first vertex welded onto the first one's apex.
        let mut m = merged(&tetrahedron(Vec3::ZERO), &tetrahedron(Vec3::Z));
        for t in &mut m.triangles[4..] {
            for i in t.iter_mut() {
                if *i == 4 {
                    *i = 3;
                }
            }
        }
        let t = topology(&m);
        assert_eq!(t.components, 1);
        assert_eq!(t.unused_vertices, 1);
        assert!(t.is_closed_manifold());
        assert_eq!(t.euler_characteristic, 7 - 12 + 8);
    }

    #[test]
    fn torus_has_euler_zero() {
        let (big, small) = (2.0f32, 0.5f32);
        let m = torus(48, 24, big, small, 0.0);
        let t = topology(&m);
        assert_eq!(t.vertices, 48 * 24);
        assert_eq!(t.edges, 3 * 48 * 24);
        assert_eq!(t.components, 1);
        assert_eq!(t.euler_characteristic, 0);
        assert!(t.is_closed_manifold());
        // Inscribed polyhedron: slightly below the smooth torus's 2 pi^2 R r^2.
        let exact = 2.0 * std::f64::consts::PI.powi(2) * f64::from(big * small * small);
        let volume = signed_volume(&m);
        assert!(
            volume < exact && volume > 0.98 * exact,
            "{volume} vs {exact}"
        );
        assert_eq!(normal_agreement(&m), 1.0);
    }

    #[test]
    fn degenerate_and_unused_are_counted_apart() {
        let mut m = cube();
        m.vertices.push(Vec3::splat(9.0));
        m.normals.push(Vec3::X);
        m.triangles.push([0, 0, 7]);
        let t = topology(&m);
        assert_eq!(t.triangles, 13);
        assert_eq!(t.degenerate_triangles, 1);
        assert_eq!(t.unused_vertices, 1);
        assert_eq!(t.edges, 18);
        assert_eq!(t.euler_characteristic, 2);
        assert!(t.is_closed_manifold());
        let comps = component_volumes(&m);
        assert_eq!(comps.len(), 1);
        assert_eq!(comps[0].0, 12);
        assert!((comps[0].1 - 1.0).abs() < 1e-12);
    }

    #[test]
    fn duplicated_triangles() {
        // On a closed mesh each edge of the copy is then used three times.
        let mut m = cube();
        m.triangles.push(m.triangles[0]);
        let t = topology(&m);
        assert_eq!(t.non_manifold_edges, 3);
        assert_eq!(t.inconsistent_edges, 0);
        // Alone, the pair walks each of its edges twice the same way.
        let pair = mesh(
            vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            vec![[0, 1, 2]; 2],
            Vec3::NEG_Z,
        );
        let t = topology(&pair);
        assert_eq!(t.edges, 3);
        assert_eq!(t.inconsistent_edges, 3);
        assert_eq!(t.boundary_edges, 0);
    }

    #[test]
    fn missing_normals_disagree_and_empty_is_nan() {
        let mut m = cube();
        m.normals.truncate(4);
        assert_eq!(normal_agreement(&m), 0.5);
        assert!(normal_agreement(&TriMesh::default()).is_nan());
        let t = topology(&TriMesh::default());
        assert_eq!(t.components, 0);
        assert_eq!(t.euler_characteristic, 0);
    }

    #[test]
    #[should_panic(expected = "references vertex 8")]
    fn out_of_range_index_panics() {
        let mut m = cube();
        m.triangles.push([0, 1, 8]);
        topology(&m);
    }

    #[test]
    fn large_torus_is_fast_and_exact() {
        // About 2 M triangles, the size of a fine reconstruction.
        let m = torus(1000, 1000, 2.0, 0.5, 0.0);
        let start = std::time::Instant::now();
        let t = topology(&m);
        let elapsed = start.elapsed();
        assert_eq!(t.triangles, 2_000_000);
        assert_eq!(t.edges, 3_000_000);
        assert_eq!(t.euler_characteristic, 0);
        assert!(t.is_closed_manifold());
        eprintln!("topology of 2 M triangles: {elapsed:?}");
    }
}
