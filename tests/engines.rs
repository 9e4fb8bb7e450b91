//! The three engines (narrow band, full gather, scatter) give the same mesh, and the full-grid
//! engines refuse grids above --max-memory.

mod common;

use common::{fixture, lattice_ball, params};
use glam::{IVec3, Vec3};
use rustc_hash::FxHashMap;
use splash::mesh::TriMesh;
use splash::recon::{Engine, Limits, reconstruct, reconstruct_with};

const R: f32 = 0.01;

/// Whether two meshes are the same up to float rounding: same vertex and triangle counts, each
/// vertex of `a` within `tol` of a vertex of `b`, and the same triangles under that matching
/// (up to rotation). The scatter engine sums each vertex's particle contributions in another
/// order than the gather (particle by particle rather than lane-wise over a gathered list), and
/// with offsets rounded from world rather than brick-local coordinates, so its field values
/// differ from the gather's in the last bits, and so do the interpolated vertices. The narrow
/// band and the full gather share the gather code and match exactly (`tol` 0).
///
/// Vertices closer than `tol` to each other (a surface through a grid vertex puts the vertices
/// of several edges there) form one group; a group must have as many vertices in both meshes,
/// and triangles are compared as triples of groups.
fn same_mesh(a: &TriMesh, b: &TriMesh, tol: f32) -> Result<(), String> {
    if a.vertices.len() != b.vertices.len() || a.triangles.len() != b.triangles.len() {
        return Err(format!(
            "{} vertices and {} triangles vs {} and {}",
            a.vertices.len(),
            a.triangles.len(),
            b.vertices.len(),
            b.triangles.len()
        ));
    }
    // Buckets of side `2 tol` (or exact positions): a match lies in one of the 27 around.
    let side = (2.0 * tol).max(f32::MIN_POSITIVE);
    let key = |v: Vec3| (v / side).floor().as_ivec3();
    let mut buckets: FxHashMap<IVec3, Vec<u32>> = FxHashMap::default();
    for (i, &v) in b.vertices.iter().enumerate() {
        buckets.entry(key(v)).or_default().push(i as u32);
    }
    // The lowest index of the vertices of `b` within `tol` of `v`.
    let group = |v: Vec3| {
        let k = key(v);
        let mut best: Option<u32> = None;
        for d in (0..27).map(|n| IVec3::new(n % 3 - 1, n / 3 % 3 - 1, n / 9 - 1)) {
            for &j in buckets.get(&(k + d)).into_iter().flatten() {
                if (b.vertices[j as usize] - v).abs().max_element() <= tol {
                    best = Some(best.map_or(j, |m| m.min(j)));
                }
            }
        }
        best
    };
    let mut count: FxHashMap<u32, i64> = FxHashMap::default();
    let mut ga = Vec::with_capacity(a.vertices.len());
    for &v in &a.vertices {
        let g = group(v).ok_or_else(|| format!("vertex {v} has no match within {tol}"))?;
        *count.entry(g).or_default() += 1;
        ga.push(g);
    }
    let gb: Vec<u32> = b.vertices.iter().map(|&v| group(v).unwrap()).collect();
    for &g in &gb {
        *count.entry(g).or_default() -= 1;
    }
    if let Some((g, n)) = count.iter().find(|(_, n)| **n != 0) {
        return Err(format!(
            "{n} more vertices near {} in the first mesh",
            b.vertices[*g as usize]
        ));
    }
    let canonical = |t: [u32; 3]| {
        let first = (0..3).min_by_key(|&i| t[i]).unwrap();
        [t[first], t[(first + 1) % 3], t[(first + 2) % 3]]
    };
    let triples = |tris: &[[u32; 3]], g: &[u32]| {
        let mut out: Vec<[u32; 3]> = tris
            .iter()
            .map(|t| canonical(t.map(|i| g[i as usize])))
            .collect();
        out.sort_unstable();
        out
    };
    let (ta, tb) = (triples(&a.triangles, &ga), triples(&b.triangles, &gb));
    match ta.iter().zip(&tb).position(|(x, y)| x != y) {
        None => Ok(()),
        Some(k) => Err(format!("triangles differ: {:?} vs {:?}", ta[k], tb[k])),
    }
}

/// Distance, in cells, from each vertex of `a` to the nearest vertex of `b`.
fn offsets(a: &TriMesh, b: &TriMesh, cell: f32) -> Vec<f32> {
    let key = |v: Vec3| (v / cell).floor().as_ivec3();
    let mut buckets: FxHashMap<IVec3, Vec<Vec3>> = FxHashMap::default();
    for &v in &b.vertices {
        buckets.entry(key(v)).or_default().push(v);
    }
    a.vertices
        .iter()
        .map(|&v| {
            (0..27)
                .map(|n| IVec3::new(n % 3 - 1, n / 3 % 3 - 1, n / 9 - 1))
                .flat_map(|d| buckets.get(&(key(v) + d)).into_iter().flatten())
                .map(|w| (*w - v).abs().max_element() / cell)
                .fold(f32::INFINITY, f32::min)
        })
        .collect()
}

fn assert_engines_agree(ps: &[Vec3], r: f32, cell: &str, what: &str) {
    let p = params(r, cell);
    let band = reconstruct(ps, &p, Engine::NarrowBand).unwrap();
    let full = reconstruct(ps, &p, Engine::FullGather).unwrap();
    let scatter = reconstruct(ps, &p, Engine::Scatter).unwrap();
    assert!(band.stats.triangles > 0, "{what}: empty mesh");
    assert_eq!(
        band.mesh.triangles.len(),
        full.mesh.triangles.len(),
        "{what}"
    );
    same_mesh(&band.mesh, &full.mesh, 0.0).unwrap_or_else(|e| panic!("{what}, full gather: {e}"));
    // Where the fluid lies against a wall of the simulation box, the surface runs almost along
    // grid edges and the field changes little along them: there a last-bit difference of the
    // field moves a vertex by up to ~2e-3 cells (measured on frame_0040: 70 of 25k vertices
    // beyond 1e-4 cells, all on the walls). Hence 1e-2 cells for every vertex, 1e-4 cells for
    // 99% of them, and the same topology.
    same_mesh(&band.mesh, &scatter.mesh, 1e-2 * p.cell)
        .unwrap_or_else(|e| panic!("{what}, scatter: {e}"));
    let off = offsets(&band.mesh, &scatter.mesh, p.cell);
    let far = off.iter().filter(|&&o| o > 1e-4).count();
    assert!(
        far * 100 <= off.len(),
        "{what}, scatter: {far} of {} vertices are more than 1e-4 cells off",
        off.len()
    );
    assert_eq!(band.stats.grid, full.stats.grid, "{what}");
    assert_eq!(band.stats.grid, scatter.stats.grid, "{what}");
}

#[test]
fn three_engines_agree_on_a_ball_with_splashes() {
    let mut ps = lattice_ball(Vec3::new(0.3, -0.2, 0.1), 6.0 * R, R);
    ps.push(Vec3::new(0.3 + 9.5 * R, -0.2, 0.1));
    ps.extend(lattice_ball(
        Vec3::new(0.3, -0.2 + 11.0 * R, 0.1),
        1.5 * R,
        R,
    ));
    for cell in ["r", "r/2"] {
        assert_engines_agree(&ps, R, cell, &format!("ball at cell {cell}"));
    }
}

#[test]
fn three_engines_agree_on_a_real_frame() {
    let ps = splash::io::read_particles(&fixture("frame_0040.ply"), None).unwrap();
    assert_engines_agree(&ps, 0.014, "r", "frame_0040 at cell r");
}

#[test]
fn full_grid_engines_refuse_above_the_memory_limit() {
    let ball = lattice_ball(Vec3::ZERO, 8.0 * R, R);
    let p = params(R, "r/2");
    let limits = Limits {
        max_memory: 100 << 10,
    };
    for engine in [Engine::FullGather, Engine::Scatter] {
        let e = match reconstruct_with(&ball, &p, engine, &limits) {
            Ok(_) => panic!("{engine:?} ran above the limit"),
            Err(e) => format!("{e:#}"),
        };
        assert!(e.contains("--max-memory") && e.contains("MB"), "{e}");
    }
    // The narrow band's memory follows the surface: no grid-sized plan to refuse.
    assert!(reconstruct_with(&ball, &p, Engine::NarrowBand, &limits).is_ok());
}
