//! The block-parallel Marching Slices engine of Rosenberg & Birdwell 2008: block subdivision
//! (Sec. 3, `blocks.rs`), Marching Slices within each block (Sec. 4, `marching.rs`, with
//! `slice_cache.rs`), the 2D-projection 1D-lookup particle cache (Sec. 6, `lookup_cache.rs`),
//! and the blocks' meshes welded into one (`weld.rs`). Blocks run in parallel; each holds its
//! lookup cache and slice caches only while it runs, so working memory is bounded per block.

pub mod blocks;
pub mod lookup_cache;
pub mod marching;
pub mod slice_cache;
pub mod weld;

use std::sync::atomic::Ordering;

use crate::error::Result;
use glam::Vec3;
use rayon::prelude::*;
use serde::Serialize;

use super::Reconstruction;
use super::prepared::{prepare, triangles_and_normals};
use crate::config::{Normals, Params};
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

pub fn reconstruct(
    particles: &[Vec3],
    params: &Params,
    checks: Checks,
    mut stages: Stages<'_>,
) -> Result<(Reconstruction, SlicesReport)> {
    let prepared = prepare(particles, params, &mut stages)?;
    let (field, samples) = prepared.sampling();
    let cell = params.cell;
    let blocks = stages.run(Stage::Band, || {
        blocks::subdivide(
            samples,
            field.support(),
            field.reach_channel(),
            cell,
            params.block as i32,
        )
    });
    let in_flight = InFlight::default();
    let setting = Setting {
        handlers: samples,
        field,
        cell,
        corner_gradients: params.normals == Normals::Grid,
        check_visits: checks.visits,
        in_flight: &in_flight,
    };
    // Each block samples the field and triangulates its cubes at once: all of it is t_sf.
    let (meshes, stats): (Vec<_>, Vec<_>) = stages.run(Stage::ScalarField, || {
        blocks.par_iter().map(|b| march(&setting, b)).unzip()
    });
    let blocks_bytes: usize = blocks.iter().map(|b| b.heap_bytes()).sum();
    drop(blocks);
    let surface_cells = stats.iter().map(|b| b.cubes_visited).sum();
    let welded = triangles_and_normals(
        &mut stages,
        params,
        field,
        || weld::weld(meshes, surface_cells),
        || Ok(samples),
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
    Ok((Reconstruction { mesh, stats: s }, report))
}
