//! The helpers of the library's unit tests: those shared with the integration and command
//! line tests (particle sets, fixtures, real frames), meshes compared up to rounding, and
//! parameters and reconstructions reached from inside the library.

use std::f32::consts::TAU;

use glam::{IVec3, Vec3};
use rustc_hash::FxHashMap;

pub use super::support::*;
use crate::config::{Config, Params};
use crate::field::FieldConfig;
use crate::length::Length;
use crate::mesh::TriMesh;

/// The default parameters (SSP07) at spacing `r` and cell size `cell`.
pub fn params(r: f32, cell: &str) -> Params {
    field_params("ssp07", r, cell)
}

/// The defaults of the field `kind` at spacing `r` and cell size `cell`.
pub fn field_params(kind: &str, r: f32, cell: &str) -> Params {
    let config = Config {
        cell: Length::parse(cell).unwrap(),
        field: FieldConfig::named(kind).unwrap(),
        ..Config::default()
    };
    Params::resolve(&config, r)
}

/// Reconstructs `particles` with `params` and `engine`, as the engines' dispatch does.
pub fn reconstruct(
    particles: &[Vec3],
    params: &Params,
    engine: crate::Engine,
) -> crate::Result<crate::Reconstruction> {
    let params = Params {
        engine,
        ..params.clone()
    };
    crate::recon::reconstruct(particles, &params, None)
}

/// A point of the unit cube from three numbers of `next` (x, y, z in that order).
pub fn uniform_point(next: &mut impl FnMut() -> f32) -> Vec3 {
    Vec3::new(next(), next(), next())
}

/// A fixed stream of pseudo-random numbers in [0, 1) from `seed` (an LCG: the tests need
/// repeatable scatter, not quality).
pub fn uniform(seed: u64) -> impl FnMut() -> f32 {
    let mut state = seed;
    move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 40) as f32 / (1u64 << 24) as f32
    }
}

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
pub fn same_mesh(a: &TriMesh, b: &TriMesh, tol: f32) -> Result<(), String> {
    if a.vertices.len() != b.vertices.len() || a.triangles.len() != b.triangles.len() {
        return Err(format!(
            "{} vertices and {} triangles vs {} and {}",
            a.vertices.len(),
            a.triangles.len(),
            b.vertices.len(),
            b.triangles.len()
        ));
    }
    // Buckets of side `2 tol` (at least 1e-4, far below the cells): a match lies in one of the
    // 27 around.
    let side = (2.0 * tol).max(1e-4);
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
pub fn offsets(a: &TriMesh, b: &TriMesh, cell: f32) -> Vec<f32> {
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

/// Torus around the z axis with its normals: radii `big` and `small`, `n` x `m` quads split in
/// two, the rings at angles (i + `phase`)·2π/n.
pub fn torus(n: u32, m: u32, big: f32, small: f32, phase: f32) -> TriMesh {
    let mut vertices = Vec::new();
    let mut normals = Vec::new();
    for i in 0..n {
        let u = TAU * (i as f32 + phase) / n as f32;
        for j in 0..m {
            let w = TAU * j as f32 / m as f32;
            let normal = Vec3::new(w.cos() * u.cos(), w.cos() * u.sin(), w.sin());
            vertices.push(Vec3::new(big * u.cos(), big * u.sin(), 0.0) + small * normal);
            normals.push(normal);
        }
    }
    let index = |i: u32, j: u32| (i % n) * m + (j % m);
    let mut triangles = Vec::new();
    for i in 0..n {
        for j in 0..m {
            let (a, b, c, d) = (
                index(i, j),
                index(i + 1, j),
                index(i + 1, j + 1),
                index(i, j + 1),
            );
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    TriMesh {
        vertices,
        normals,
        triangles,
    }
}

/// Frames 1..=`count` of balls of particles on a lattice of spacing 0.1 with a velocity
/// `(y, 0, frame)`, one CSV per frame (`f_{frame}.csv`) in `dir`, the radius growing with the
/// frame number.
pub fn ball_frames(dir: &std::path::Path, count: u32) -> Vec<std::path::PathBuf> {
    (1..=count)
        .map(|f| {
            let mut text = String::from("x,y,z,vx,vy,vz\n");
            let radius = 0.3 + 0.1 * f as f32;
            for (x, y, z) in
                (-6..=6).flat_map(|x| (-6..=6).flat_map(move |y| (-6..=6).map(move |z| (x, y, z))))
            {
                let p = Vec3::new(x as f32, y as f32, z as f32) * 0.1;
                if p.length() <= radius {
                    text += &format!("{},{},{},{},0,{}\n", p.x, p.y, p.z, p.y, f);
                }
            }
            let path = dir.join(format!("f_{f}.csv"));
            std::fs::write(&path, text).unwrap();
            path
        })
        .collect()
}

/// `a` and `b` as one mesh: `b`'s triangles renumbered past `a`'s vertices, the normals of
/// both kept.
pub fn merged(a: &TriMesh, b: &TriMesh) -> TriMesh {
    let shift = a.vertices.len() as u32;
    TriMesh {
        vertices: [a.vertices.as_slice(), &b.vertices].concat(),
        normals: [a.normals.as_slice(), &b.normals].concat(),
        triangles: a
            .triangles
            .iter()
            .copied()
            .chain(b.triangles.iter().map(|t| t.map(|i| i + shift)))
            .collect(),
    }
}

/// The unit sphere as an octahedron whose faces are split in four `level` times, the new
/// vertices pushed onto the sphere; closed and wound counter-clockwise seen from outside.
pub fn octasphere(level: u32) -> TriMesh {
    let mut vertices = vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
    let mut triangles: Vec<[u32; 3]> = vec![
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];
    for _ in 0..level {
        let mut middles = std::collections::HashMap::new();
        let mut middle = |a: u32, b: u32, vertices: &mut Vec<Vec3>| {
            *middles.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let m = (vertices[a as usize] + vertices[b as usize]).normalize();
                vertices.push(m);
                vertices.len() as u32 - 1
            })
        };
        let mut split = Vec::with_capacity(triangles.len() * 4);
        for [a, b, c] in triangles {
            let (ab, bc, ca) = (
                middle(a, b, &mut vertices),
                middle(b, c, &mut vertices),
                middle(c, a, &mut vertices),
            );
            split.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        triangles = split;
    }
    TriMesh {
        normals: vertices.clone(),
        vertices,
        triangles,
    }
}
