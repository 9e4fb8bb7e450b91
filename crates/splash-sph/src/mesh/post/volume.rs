//! Volume restoration: each closed component of the mesh is offset along its vertex normals
//! until it encloses a target volume, N_c·r³ for the N_c particles inside it (incompressible
//! SPH keeps each particle's volume r³), so that neither the field's inflation of sheets and
//! droplets nor smoothing's shrinkage changes how much fluid a frame shows.

use glam::{DVec3, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::clearance::Clearance;
use crate::mesh::adjacency::{Neighbours, VertexFaces};
use crate::mesh::area_normal;

/// What the volume steps of `PostConfig` restore: see `PostConfig::volume_scope`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum VolumeScope {
    /// The whole mesh: one offset for every vertex.
    Frame,
    /// Each closed component: its own offset.
    Component,
}

impl VolumeScope {
    /// The scope's name in configs and on the command line: `frame` or `component`.
    pub fn name(self) -> &'static str {
        match self {
            VolumeScope::Frame => "frame",
            VolumeScope::Component => "component",
        }
    }

    /// The scope of a [`name`](Self::name).
    pub fn parse(text: &str) -> crate::error::Result<VolumeScope> {
        match text.trim() {
            "frame" => Ok(VolumeScope::Frame),
            "component" => Ok(VolumeScope::Component),
            _ => Err(crate::error::Error::config(format!(
                "unknown volume scope '{text}': expected frame or component"
            ))),
        }
    }
}

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
    /// Labels the components by a walk over the neighbour rows.
    pub fn new(rings: &Neighbours) -> Components {
        let n = rings.vertices();
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
                // Every edge is walked away from one of its ends by some triangle, so the
                // neighbour rows reach the whole component.
                for &u in rings.of(v as usize) {
                    if of_vertex[u as usize] == u32::MAX {
                        of_vertex[u as usize] = count;
                        queue.push(u);
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

    /// Signed volume and area of each component, summed in `f64` over the triangles in order
    /// (for the targets; the volume steps use [`Components::sums`]).
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

    /// Volume and area of each component from the [`Measures`]: their runs of vertices in
    /// order (the same sums on any thread count).
    pub fn sums(&self, measures: &Measures) -> Vec<(f64, f64)> {
        let mut out = vec![(0.0, 0.0); self.count];
        for &(c, [v, a]) in measures.runs.iter().flatten() {
            let entry = &mut out[c as usize];
            entry.0 += v;
            entry.1 += a;
        }
        out
    }
}

/// Vertices per parallel task of [`normals_and_measures`] (and per run of its sums).
const CHUNK: usize = 4096;

/// Each component's share of the volume and area, from N_v, the sum of the (twice-area)
/// normals of the triangles around each vertex v: Σ_v (p_v − o)·N_v = 18 V for any origin o
/// (each triangle's three corners give 3·6 times its signed tetrahedron), and Σ_v |N_v| / 6 ≤
/// the area, equal where the surface is flat (enough for the size of a volume step). Summed
/// per component over runs of 4096 vertices, not kept per vertex (16 bytes a vertex less
/// at the post-processing's peak).
#[derive(Debug, Clone, Default)]
pub struct Measures {
    /// Per run of vertices, the components it meets, in order of first vertex, with their
    /// shares of the volume and the area.
    runs: Vec<Vec<(u32, [f64; 2])>>,
    /// Per triangle, its twice-area normal: each made once and read by its three corners
    /// (a buffer kept between the calls, lent out as scratch between them).
    crosses: Vec<Vec3>,
}

impl Measures {
    /// The buffer of the triangles' normals as `len` entries of scratch (grown if shorter),
    /// for work between two [`normals_and_measures`], so that smoothing and the measures
    /// share one array.
    pub fn scratch(&mut self, len: usize) -> &mut [Vec3] {
        if self.crosses.is_empty() {
            // Zeroed pages rather than a fill on one thread.
            self.crosses = vec![Vec3::ZERO; len];
        } else if self.crosses.len() < len {
            self.crosses.resize(len, Vec3::ZERO);
        }
        &mut self.crosses[..len]
    }
}

/// Unit area-weighted vertex normals into `normals` and each component's [`Measures`]: the
/// triangles' normals first, then a pass over the one-rings.
pub fn normals_and_measures(
    vertices: &[Vec3],
    triangles: &[[u32; 3]],
    rings: &VertexFaces,
    components: &Components,
    normals: &mut [Vec3],
    measures: &mut Measures,
) {
    let origin = vertices.first().copied().unwrap_or_default();
    let crosses = measures.scratch(triangles.len());
    crosses
        .par_chunks_mut(CHUNK)
        .zip(triangles.par_chunks(CHUNK))
        .for_each(|(crosses, triangles)| {
            for (n, t) in crosses.iter_mut().zip(triangles) {
                *n = area_normal(t, vertices);
            }
        });
    let Measures { runs, crosses } = measures;
    let crosses = &crosses[..triangles.len()];
    runs.resize(normals.len().div_ceil(CHUNK), Vec::new());
    normals
        .par_chunks_mut(CHUNK)
        .zip(runs.par_iter_mut())
        .enumerate()
        .for_each(|(c, (normals, run))| {
            run.clear();
            for (k, n) in normals.iter_mut().enumerate() {
                let v = c * CHUNK + k;
                let mut sum = Vec3::ZERO;
                for f in rings.of(v) {
                    sum += crosses[f];
                }
                *n = sum.normalize_or_zero();
                let component = components.of_vertex[v];
                if component == u32::MAX {
                    continue;
                }
                let p = vertices[v] - origin;
                let share = [
                    p.as_dvec3().dot(sum.as_dvec3()) / 18.0,
                    f64::from(sum.length()) / 6.0,
                ];
                // A run's vertices mostly continue the component of the one before.
                let i = match run.iter().rposition(|e| e.0 == component) {
                    Some(i) => i,
                    None => {
                        run.push((component, [0.0; 2]));
                        run.len() - 1
                    }
                };
                run[i].1[0] += share[0];
                run[i].1[1] += share[1];
            }
        });
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
    let others: Vec<u32> = (0..triangles.len() as u32)
        .filter(|&f| components.of_vertex[triangles[f as usize][0] as usize] != main as u32)
        .collect();
    if others.is_empty() {
        counts[main] = particles.len();
        return counts;
    }
    // xy bins of two cells (more where the others spread over more than 2048 of them, to
    // bound the grid), holding the triangles of the other components as rows.
    let (mut lo_xy, mut hi_xy) = (glam::DVec2::MAX, glam::DVec2::MIN);
    for &f in &others {
        for i in triangles[f as usize] {
            let p = vertices[i as usize].as_dvec3().truncate();
            (lo_xy, hi_xy) = (lo_xy.min(p), hi_xy.max(p));
        }
    }
    let bin = (2.0 * f64::from(cell)).max((hi_xy - lo_xy).max_element() / 2048.0);
    let key = |x: f64, y: f64| ((x / bin).floor() as i32, (y / bin).floor() as i32);
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
    // A dense grid of bins over the other triangles' xy box, rows of triangle indices.
    let lo = spans.iter().fold((i32::MAX, i32::MAX), |a, s| {
        (a.0.min(s.0.0), a.1.min(s.0.1))
    });
    let hi = spans.iter().fold((i32::MIN, i32::MIN), |a, s| {
        (a.0.max(s.1.0), a.1.max(s.1.1))
    });
    let (nx, ny) = ((hi.0 - lo.0 + 1) as usize, (hi.1 - lo.1 + 1) as usize);
    let bin_of = |(x, y): (i32, i32)| -> Option<usize> {
        let (i, j) = (x.checked_sub(lo.0)?, y.checked_sub(lo.1)?);
        ((0..nx as i32).contains(&i) && (0..ny as i32).contains(&j))
            .then(|| j as usize * nx + i as usize)
    };
    let mut starts = vec![0u32; nx * ny + 1];
    for &(a, b) in &spans {
        for y in a.1..=b.1 {
            for x in a.0..=b.0 {
                starts[bin_of((x, y)).unwrap() + 1] += 1;
            }
        }
    }
    for k in 0..nx * ny {
        starts[k + 1] += starts[k];
    }
    let mut fill = starts.clone();
    let mut binned = vec![0u32; starts[nx * ny] as usize];
    for (&f, &(a, b)) in others.iter().zip(&spans) {
        for y in a.1..=b.1 {
            for x in a.0..=b.0 {
                let k = bin_of((x, y)).unwrap();
                binned[fill[k] as usize] = f;
                fill[k] += 1;
            }
        }
    }
    // Each component's box: a particle outside it is not inside the component, whatever the
    // ray crosses (most particles under a droplet's column are in the fluid below it).
    let mut boxes = vec![(DVec3::MAX, DVec3::MIN); components.count];
    for (p, &c) in vertices.iter().zip(&components.of_vertex) {
        if c != u32::MAX {
            let b = &mut boxes[c as usize];
            (b.0, b.1) = (b.0.min(p.as_dvec3()), b.1.max(p.as_dvec3()));
        }
    }
    // A fixed tiny shift of every ray off the grid's planes, on which Marching Cubes' vertices
    // and lattice particles lie, so that no ray passes through a vertex or along an edge.
    let shift = DVec3::new(0.318_309_886e-3, 0.577_215_664e-3, 0.0) * f64::from(cell);
    let inside: Vec<u32> = particles
        .par_iter()
        .map_init(Vec::new, |parity: &mut Vec<u32>, p| {
            let q = p.as_dvec3() + shift;
            let Some(b) = bin_of(key(q.x, q.y)) else {
                return u32::MAX;
            };
            parity.clear();
            for &f in &binned[starts[b] as usize..starts[b + 1] as usize] {
                let t = triangles[f as usize];
                let c = components.of_vertex[t[0] as usize];
                let (lo, hi) = boxes[c as usize];
                if q.cmplt(lo).any() || q.cmpgt(hi).any() {
                    continue;
                }
                if crosses_above(q, t.map(|i| vertices[i as usize].as_dvec3())) {
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

/// Offsets each component (or, for [`VolumeScope::Frame`], the whole mesh) along its unit
/// vertex normals by (target − volume)/area, the first-order change, at most `max_step` and
/// as far as each vertex's `clearance` lets it, `steps` times, `normals` and `measures`
/// ([`normals_and_measures`]) made before each step but not after the last (the caller smooths
/// again, or recomputes them once). The curvature's error of one step falls to a fraction of a
/// percent after three. No targets: nothing to do.
#[allow(clippy::too_many_arguments)]
pub fn restore(
    vertices: &mut [Vec3],
    normals: &mut [Vec3],
    measures: &mut Measures,
    triangles: &[[u32; 3]],
    rings: &VertexFaces,
    components: &Components,
    targets: &[f64],
    scope: VolumeScope,
    clearance: &mut Clearance,
    steps: u32,
    max_step: f32,
) {
    if targets.is_empty() {
        return;
    }
    for _ in 0..steps {
        normals_and_measures(vertices, triangles, rings, components, normals, measures);
        let offsets: Vec<f32> = first_order_offsets(&components.sums(measures), targets, scope)
            .into_iter()
            .map(|o| o.clamp(-max_step, max_step))
            .collect();
        clearance.offset(vertices, normals, &components.of_vertex, &offsets);
    }
}

/// Per component, the offset along the normals that brings it to its target to first order,
/// (target − volume)/area from its `sums` (volume and area); for [`VolumeScope::Frame`] one
/// for the whole mesh, repeated. 0 for a component without area.
pub fn first_order_offsets(sums: &[(f64, f64)], targets: &[f64], scope: VolumeScope) -> Vec<f32> {
    let offset = |(v, a): (f64, f64), t: f64| if a > 0.0 { ((t - v) / a) as f32 } else { 0.0 };
    match scope {
        VolumeScope::Component => sums
            .iter()
            .zip(targets)
            .map(|(&s, &t)| offset(s, t))
            .collect(),
        VolumeScope::Frame => {
            let (mut all, mut target) = ((0.0, 0.0), 0.0);
            for (&(v, a), &t) in sums.iter().zip(targets) {
                all = (all.0 + v, all.1 + a);
                target += t;
            }
            vec![offset(all, target); sums.len()]
        }
    }
}
