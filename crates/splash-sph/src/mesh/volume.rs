//! Volume restoration: each closed component of the mesh is offset along its vertex normals
//! until it encloses a target volume, N_c·r³ for the N_c particles inside it (incompressible
//! SPH keeps each particle's volume r³), so that neither the field's inflation of sheets and
//! droplets nor smoothing's shrinkage changes how much fluid a frame shows.

use glam::{DVec3, Vec3};
use rayon::prelude::*;
use rustc_hash::FxHashMap;

use super::adjacency::VertexFaces;
use super::smoothing::vertex_normals;

/// The connected components of a mesh (vertex connectivity through triangles).
#[derive(Debug, Clone)]
pub struct Components {
    /// Component of each vertex (u32::MAX for a vertex no triangle uses), numbered in order of
    /// each component's smallest vertex.
    pub of_vertex: Vec<u32>,
    /// Number of components.
    pub count: usize,
}

impl Components {
    /// Labels the components by a breadth-first walk over the triangles around each vertex.
    pub fn new(triangles: &[[u32; 3]], rings: &VertexFaces) -> Components {
        let n = rings.offsets.len() - 1;
        let mut of_vertex = vec![u32::MAX; n];
        let mut queue = Vec::new();
        let mut count = 0u32;
        for seed in 0..n {
            if of_vertex[seed] != u32::MAX || rings.of(seed).is_empty() {
                continue;
            }
            of_vertex[seed] = count;
            queue.push(seed as u32);
            while let Some(v) = queue.pop() {
                for &f in rings.of(v as usize) {
                    for u in triangles[f as usize] {
                        if of_vertex[u as usize] == u32::MAX {
                            of_vertex[u as usize] = count;
                            queue.push(u);
                        }
                    }
                }
            }
            count += 1;
        }
        Components {
            of_vertex,
            count: count as usize,
        }
    }

    /// Signed volume and area of each component, summed in `f64` over the triangles in order.
    pub fn volumes_and_areas(&self, vertices: &[Vec3], triangles: &[[u32; 3]]) -> Vec<(f64, f64)> {
        let mut out = vec![(0.0, 0.0); self.count];
        for t in triangles {
            let c = self.of_vertex[t[0] as usize];
            let [a, b, d] = t.map(|i| vertices[i as usize].as_dvec3());
            let entry = &mut out[c as usize];
            entry.0 += a.dot(b.cross(d)) / 6.0;
            entry.1 += 0.5 * (b - a).cross(d - a).length();
        }
        out
    }
}

/// How many of `particles` lie inside each component: by the parity of the crossings of a ray
/// along +z with the component's triangles, for every component but the one of largest volume,
/// which gets the particles left over (counting it would test most particles against many
/// triangles; the others are droplets and sheets, few triangles over few particles). `cell`
/// sizes the xy bins of the triangles.
pub fn particles_inside(
    components: &Components,
    volumes: &[(f64, f64)],
    vertices: &[Vec3],
    triangles: &[[u32; 3]],
    particles: &[Vec3],
    cell: f32,
) -> Vec<usize> {
    let mut counts = vec![0usize; components.count];
    let Some(main) = (0..components.count).max_by(|&a, &b| volumes[a].0.total_cmp(&volumes[b].0))
    else {
        return counts;
    };
    // xy bins of two cells holding the triangles of the other components, as rows.
    let bin = 2.0 * f64::from(cell);
    let key = |x: f64, y: f64| ((x / bin).floor() as i32, (y / bin).floor() as i32);
    let others: Vec<u32> = (0..triangles.len() as u32)
        .filter(|&f| components.of_vertex[triangles[f as usize][0] as usize] != main as u32)
        .collect();
    if others.is_empty() {
        counts[main] = particles.len();
        return counts;
    }
    let mut bins: FxHashMap<(i32, i32), u32> = FxHashMap::default();
    let mut rows: Vec<u32> = Vec::new();
    let spans: Vec<((i32, i32), (i32, i32))> = others
        .iter()
        .map(|&f| {
            let p = triangles[f as usize].map(|i| vertices[i as usize].as_dvec3());
            let lo = key(
                p[0].x.min(p[1].x).min(p[2].x),
                p[0].y.min(p[1].y).min(p[2].y),
            );
            let hi = key(
                p[0].x.max(p[1].x).max(p[2].x),
                p[0].y.max(p[1].y).max(p[2].y),
            );
            (lo, hi)
        })
        .collect();
    for &(lo, hi) in &spans {
        for x in lo.0..=hi.0 {
            for y in lo.1..=hi.1 {
                let next = bins.len() as u32;
                let b = *bins.entry((x, y)).or_insert(next);
                if b as usize == rows.len() {
                    rows.push(0);
                }
                rows[b as usize] += 1;
            }
        }
    }
    let mut starts = vec![0u32; rows.len() + 1];
    for b in 0..rows.len() {
        starts[b + 1] = starts[b] + rows[b];
    }
    let mut fill = starts.clone();
    let mut binned = vec![0u32; starts[rows.len()] as usize];
    for (&f, &(lo, hi)) in others.iter().zip(&spans) {
        for x in lo.0..=hi.0 {
            for y in lo.1..=hi.1 {
                let b = bins[&(x, y)] as usize;
                binned[fill[b] as usize] = f;
                fill[b] += 1;
            }
        }
    }
    // A fixed tiny shift of every ray off the grid's planes, on which Marching Cubes' vertices
    // and lattice particles lie, so that no ray passes through a vertex or along an edge.
    let shift = DVec3::new(0.318_309_886e-3, 0.577_215_664e-3, 0.0) * f64::from(cell);
    let inside: Vec<u32> = particles
        .par_iter()
        .map_init(Vec::new, |parity: &mut Vec<u32>, p| {
            let q = p.as_dvec3() + shift;
            let Some(&b) = bins.get(&key(q.x, q.y)) else {
                return u32::MAX;
            };
            parity.clear();
            for &f in &binned[starts[b as usize] as usize..starts[b as usize + 1] as usize] {
                let t = triangles[f as usize];
                if crosses_above(q, t.map(|i| vertices[i as usize].as_dvec3())) {
                    let c = components.of_vertex[t[0] as usize];
                    // Toggle c in the odd set.
                    match parity.iter().position(|&x| x == c) {
                        Some(i) => {
                            parity.swap_remove(i);
                        }
                        None => parity.push(c),
                    }
                }
            }
            // Nested components (a droplet in a bubble): the innermost, the smallest volume.
            parity
                .iter()
                .copied()
                .min_by(|&a, &b| {
                    volumes[a as usize]
                        .0
                        .abs()
                        .total_cmp(&volumes[b as usize].0.abs())
                })
                .unwrap_or(u32::MAX)
        })
        .collect();
    for c in inside {
        if c != u32::MAX {
            counts[c as usize] += 1;
        }
    }
    counts[main] = particles.len() - counts.iter().sum::<usize>();
    counts
}

/// Whether the ray from `q` along +z crosses the triangle `p` (in its xy projection, strictly
/// inside, above q).
fn crosses_above(q: DVec3, p: [DVec3; 3]) -> bool {
    let edge = |a: DVec3, b: DVec3| (b.x - a.x) * (q.y - a.y) - (b.y - a.y) * (q.x - a.x);
    let (e0, e1, e2) = (edge(p[0], p[1]), edge(p[1], p[2]), edge(p[2], p[0]));
    let inside = (e0 > 0.0 && e1 > 0.0 && e2 > 0.0) || (e0 < 0.0 && e1 < 0.0 && e2 < 0.0);
    if !inside {
        return false;
    }
    // Barycentric height of the triangle at q.
    let s = e0 + e1 + e2;
    let z = (e1 * p[0].z + e2 * p[1].z + e0 * p[2].z) / s;
    z > q.z
}

/// Offsets each component along its unit vertex normals `normals` (recomputed after each
/// step) by (target − volume)/area, the first-order change, `steps` times: the curvature's
/// error of one step falls to a fraction of a percent after three. A step moves at most
/// `max_step`.
#[allow(clippy::too_many_arguments)]
pub fn restore(
    vertices: &mut [Vec3],
    normals: &mut [Vec3],
    triangles: &[[u32; 3]],
    rings: &VertexFaces,
    components: &Components,
    targets: &[f64],
    steps: u32,
    max_step: f32,
) {
    for _ in 0..steps {
        let sums = components.volumes_and_areas(vertices, triangles);
        let offsets: Vec<f32> = sums
            .iter()
            .zip(targets)
            .map(|(&(v, a), &t)| {
                if a > 0.0 {
                    (((t - v) / a) as f32).clamp(-max_step, max_step)
                } else {
                    0.0
                }
            })
            .collect();
        vertices
            .par_iter_mut()
            .zip(normals.par_iter())
            .zip(components.of_vertex.par_iter())
            .for_each(|((p, n), &c)| {
                if c != u32::MAX {
                    *p += offsets[c as usize] * *n;
                }
            });
        vertex_normals(vertices, triangles, rings, normals);
    }
}
