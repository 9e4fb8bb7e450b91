//! The baselines of Rosenberg & Birdwell 2008, Fig. 7, against which the paper measures
//! Marching Slices: surface-following Marching Cubes (`follow.rs`) with (2) block subdivision,
//! 3D corner arrays and a voxel-grid particle cache (`blocked.rs`), or (3) hash maps for the
//! corners and the particle grid, unbounded (`hashed.rs`). Both are seeded as the slices engine
//! is and sample the field as it does (`sampler.rs`, `particle_grid.rs`), so all three give the
//! same mesh and differ only in their data structures; `splash bench slices` compares them.

pub mod blocked;
pub mod follow;
pub mod hashed;
pub mod particle_grid;
pub mod sampler;

use std::sync::atomic::Ordering;

use glam::Vec3;
use rayon::prelude::*;
use rustc_hash::FxHashMap;

use super::marching_slices::marching::{InFlight, Setting};
use super::marching_slices::{blocks, weld};
use super::prepared::{Reconstruction, prepare};
use crate::config::{Baseline, Normals, Params};
use crate::error::Result;
use crate::recon::budget::{self, mul};
use crate::report::{SlicesFigures, Stage, Stages};

/// The figures of a block, or of approach 3's one unbounded run.
#[derive(Debug, Clone, Copy, Default)]
pub struct Figures {
    pub cubes_visited: usize,
    /// Corners whose field was sampled.
    pub corners: usize,
    /// Peak bytes of the corner caches and the todo stack: the paper's "render memory".
    pub render_bytes: usize,
    /// Bytes of the particle grid and the particles' copies and list: its "cache memory".
    pub cache_bytes: usize,
}

/// Heap bytes of a hash map as hashbrown lays it out: a power of two of buckets at most 7/8
/// full, each a (key, value) and a control byte, and a group of control bytes more.
fn hash_bytes<K, V>(map: &FxHashMap<K, V>) -> usize {
    let capacity = map.capacity();
    if capacity == 0 {
        return 0;
    }
    let buckets = if capacity < 8 {
        (capacity + 1).next_power_of_two()
    } else {
        (capacity * 8 / 7).next_power_of_two()
    };
    buckets * (size_of::<(K, V)>() + 1) + 16
}

/// Bytes per particle of a block's copies and grid: position (12), cube units (24), the
/// grid's entry (4), its own reach (8) and the block's list (4).
const PER_BLOCK_PARTICLE: u64 = 12 + 24 + 4 + 8 + 4;

/// The mesh of `particles` by `baseline`, the slices engine's mesh (the same triangles and
/// vertices; the triangles in another order), with the figures of Fig. 7 in `stats.slices`
/// (render and cache memory) and `stats.surface_cells` (cubes visited).
pub fn reconstruct(
    particles: &[Vec3],
    params: &Params,
    baseline: Baseline,
    mut stages: Stages<'_>,
) -> Result<Reconstruction> {
    let prepared = prepare(particles, params, &mut stages, None)?;
    let (field, samples) = prepared.sampling();
    let held = prepared.heap_bytes() as u64;
    let (cell, n) = (params.cell, particles.len());
    let blocks = blocks::subdivide_within_limit(&mut stages, params, field, samples, held)?;
    let lists: u64 = blocks.iter().map(|b| b.heap_bytes() as u64).sum();
    let corner_gradients = params.normals == Normals::Grid;
    // The working memory: per block in flight (2), or the corners of the whole surface (3),
    // besides the particles' copies, the blocks' lists and the mesh.
    let cubes = params.block as i32 + 2 * blocks::margin(field.support(), cell);
    let vertices = budget::mesh_vertices(params, budget::surface_guess(n));
    let working = match baseline {
        Baseline::BlockedCubes => {
            let fullest = blocks.iter().map(|b| b.particles.len()).max().unwrap_or(0) as u64;
            mul(
                blocked::array_bytes(cubes, corner_gradients)
                    .saturating_add(mul(fullest, PER_BLOCK_PARTICLE)),
                rayon::current_num_threads() as u64,
            )
        }
        // The corner map: 168-178 bytes per mesh vertex on the fixture (metaball, r/2 and
        // 0.375r), as its table doubles.
        Baseline::HashedCubes => {
            mul(n as u64, PER_BLOCK_PARTICLE).saturating_add(mul(vertices, 192))
        }
    };
    stages.stats.planned_bytes = budget::check(
        params,
        held.saturating_add(lists)
            .saturating_add(working)
            .saturating_add(budget::mesh_bytes(vertices)),
        || format!("the {baseline:?} baseline's corner caches and particle grids"),
    )?;
    let in_flight = InFlight::default();
    let set = Setting {
        handlers: samples,
        field,
        cell,
        spacing: params.spacing,
        corner_gradients,
        check_visits: false,
        in_flight: &in_flight,
    };
    let (meshes, figures): (Vec<_>, Vec<Figures>) = stages.run(Stage::ScalarField, || {
        Ok::<_, crate::error::Error>(match baseline {
            Baseline::BlockedCubes => blocks
                .par_iter()
                .map(|b| blocked::march(&set, b))
                .collect::<Result<Vec<_>>>()?
                .into_iter()
                .unzip(),
            Baseline::HashedCubes => {
                let (mesh, f) = hashed::march(&set, &blocks)?;
                in_flight.add(f.render_bytes + f.cache_bytes);
                (vec![mesh], vec![f])
            }
        })
    })?;
    drop(blocks);
    let surface_cells = figures.iter().map(|f| f.cubes_visited).sum();
    let welded = weld::weld_and_finish(
        &mut stages,
        params,
        field,
        samples,
        held,
        meshes,
        surface_cells,
        "the welded mesh",
    )?;
    let mut s = stages.stats;
    let mesh = welded.mesh;
    let count = figures.len().max(1);
    let max = |k: fn(&Figures) -> usize| figures.iter().map(k).max().unwrap_or(0);
    let sum = |k: fn(&Figures) -> usize| figures.iter().map(k).sum::<usize>();
    s.slices = SlicesFigures {
        blocks: if baseline == Baseline::BlockedCubes {
            figures.len()
        } else {
            0
        },
        peak_slices: 0,
        render_bytes_max: max(|f| f.render_bytes),
        render_bytes_mean: sum(|f| f.render_bytes) / count,
        cache_bytes_max: max(|f| f.cache_bytes),
        cache_bytes_mean: sum(|f| f.cache_bytes) / count,
        in_flight_peak: in_flight.peak.load(Ordering::Relaxed),
    };
    s.bricks = welded.brick_vertices.len();
    s.surface_vertices = sum(|f| f.corners);
    s.surface_cells = welded.surface_cells;
    s.triangles = mesh.triangles.len();
    s.vertices = mesh.vertices.len();
    s.peak_bytes =
        prepared.heap_bytes() + lists as usize + s.slices.in_flight_peak + mesh.heap_bytes();
    s.heap_peak = s.stage_heap.max();
    Ok(Reconstruction::new(mesh, s))
}
