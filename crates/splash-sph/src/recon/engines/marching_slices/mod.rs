//! The block-parallel Marching Slices engine of Rosenberg & Birdwell 2008: block subdivision
//! (Sec. 3, `blocks.rs`), Marching Slices within each block (Sec. 4, `marching.rs`, with
//! `slice_cache.rs`), the 2D-projection 1D-lookup particle cache (Sec. 6, `lookup_cache.rs`),
//! the seeds (`seeds.rs`) and seeds for what they miss (`missed_seeds.rs`), and the blocks'
//! meshes welded into one (`weld.rs`). Blocks run in parallel; each holds its
//! lookup cache and slice caches only while it runs, so working memory is bounded per block.

pub mod blocks;
pub mod lookup_cache;
pub mod marching;
pub mod missed_seeds;
pub mod seeds;
pub mod slice_cache;
pub mod weld;

use std::sync::atomic::Ordering;

use crate::error::Result;
use glam::Vec3;
use rayon::prelude::*;
use serde::Serialize;

use super::prepared::Reconstruction;
use super::prepared::prepare;
use crate::bytes::human;
use crate::config::{Normals, Params};
use crate::recon::budget::{self, mul};
use crate::report::{SlicesFigures, Stage, Stages};
use marching::{BlockStats, InFlight, Setting, march};

/// The engine's figures for one frame.
#[derive(Debug, Clone, Default, Serialize)]
pub struct SlicesReport {
    pub blocks: Vec<BlockStats>,
    /// Peak bytes of lookup and slice caches of all blocks in flight at once.
    pub in_flight_peak: usize,
}

impl SlicesReport {
    pub fn max(&self, f: impl Fn(&BlockStats) -> usize) -> usize {
        self.blocks.iter().map(f).max().unwrap_or(0)
    }
}

/// Options for tests.
#[derive(Debug, Clone, Copy, Default)]
pub struct Checks {
    /// Count visits to cubes already visited (keeps a set of every visited cube).
    pub visits: bool,
}

/// Heap bytes per mesh vertex of the blocks' meshes and their weld: per block its edge (16),
/// position (12) and two triangles (24), then the weld's order (16) and remap (4), the mesh
/// (24 + 24 for two triangles) and the field normals' gradients (12); vertices on block
/// faces count twice, a few percent.
const PER_SLICES_MESH_VERTEX: u64 = 16 + 12 + 24 + 16 + 4 + 48 + 12;

pub fn reconstruct(
    particles: &[Vec3],
    params: &Params,
    checks: Checks,
    mut stages: Stages<'_>,
) -> Result<(Reconstruction, SlicesReport)> {
    let prepared = prepare(particles, params, &mut stages, None)?;
    let (field, samples) = prepared.sampling();
    let cell = params.cell;
    let held = prepared.heap_bytes() as u64;
    let n = particles.len();
    let (reach, channels) = (field.support() / cell, samples.channels.len());
    let size = params.block as i32;
    // The fullest block, guessed before the blocks are built: a cell far smaller than the
    // reach gives blocks of thousands of lookup entries per particle.
    let fullest = blocks::fullest_block_guess(samples, field.support(), cell, size);
    let cubes = size + 2 * blocks::margin(field.support(), cell);
    let block = blocks::block_bytes(fullest, cubes, channels, reach);
    budget::check(params, held.saturating_add(block), || {
        format!(
            "a block of {cubes}³ cubes with its margins holding about {fullest} particles, \
             each reaching {:.0} cubes",
            reach.ceil()
        )
    })?;
    let blocks = blocks::subdivide_within_limit(&mut stages, params, field, samples, held)?;
    // The blocks in flight at once (the largest, one per thread), their particle lists, and
    // the mesh: the blocks' parts, then the welded mesh and its sort.
    let mut per_block: Vec<u64> = blocks
        .iter()
        .map(|b| b.planned_bytes(channels, reach))
        .collect();
    per_block.sort_unstable_by(|a, b| b.cmp(a));
    let in_flight: u64 = per_block
        .iter()
        .take(rayon::current_num_threads())
        .fold(0, |a, &b| a.saturating_add(b));
    let lists: u64 = blocks.iter().map(|b| b.heap_bytes() as u64).sum();
    let vertices = budget::mesh_vertices(params, budget::surface_guess(n));
    let need = held
        .saturating_add(lists)
        .saturating_add(in_flight)
        .saturating_add(mul(vertices, PER_SLICES_MESH_VERTEX));
    stages.stats.planned_bytes = budget::check(params, need, || {
        format!(
            "{} blocks of {}³ cubes (the largest holds {} particles: {} in flight per thread) \
             and a mesh of about {vertices} vertices",
            blocks.len(),
            params.block,
            blocks.iter().map(|b| b.particles.len()).max().unwrap_or(0),
            human(per_block.first().copied().unwrap_or(0))
        )
    })?;
    let in_flight = InFlight::default();
    let setting = Setting {
        handlers: samples,
        field,
        cell,
        spacing: params.spacing,
        corner_gradients: params.normals == Normals::Grid,
        check_visits: checks.visits,
        in_flight: &in_flight,
    };
    // Each block samples the field and triangulates its cubes at once: all of it is t_sf.
    let marched: Vec<_> = stages.run(Stage::ScalarField, || {
        blocks
            .par_iter()
            .map(|b| march(&setting, b))
            .collect::<Result<_>>()
    })?;
    let (meshes, stats): (Vec<_>, Vec<_>) = marched.into_iter().unzip();
    let blocks_bytes: usize = blocks.iter().map(|b| b.heap_bytes()).sum();
    drop(blocks);
    let surface_cells = stats.iter().map(|b| b.cubes_visited).sum();
    let welded = weld::weld_and_finish(
        &mut stages,
        params,
        field,
        samples,
        held,
        meshes,
        surface_cells,
        "the welded mesh of the blocks",
    )?;
    let report = SlicesReport {
        in_flight_peak: in_flight.peak.load(Ordering::Relaxed),
        blocks: stats,
    };
    let mut s = stages.stats;
    let mesh = welded.mesh;
    let blocks = report.blocks.len().max(1);
    s.slices = SlicesFigures {
        blocks: report.blocks.len(),
        peak_slices: report.max(|b| b.peak_slices),
        render_bytes_max: report.max(|b| b.render_bytes),
        render_bytes_mean: report.blocks.iter().map(|b| b.render_bytes).sum::<usize>() / blocks,
        cache_bytes_max: report.max(|b| b.cache_bytes),
        cache_bytes_mean: report.blocks.iter().map(|b| b.cache_bytes).sum::<usize>() / blocks,
        in_flight_peak: report.in_flight_peak,
    };
    s.bricks = welded.brick_vertices.len();
    s.surface_vertices = report.blocks.iter().map(|b| b.corners).sum();
    s.surface_cells = welded.surface_cells;
    s.triangles = mesh.triangles.len();
    s.vertices = mesh.vertices.len();
    s.peak_bytes = prepared.heap_bytes() + blocks_bytes + report.in_flight_peak + mesh.heap_bytes();
    s.heap_peak = s.stage_heap.max();
    Ok((Reconstruction::new(mesh, s), report))
}
