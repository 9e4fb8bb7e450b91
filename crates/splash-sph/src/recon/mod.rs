//! Surface reconstruction engines behind one signature: [`reconstruct`] runs the engine that
//! the parameters name. Each engine runs the stages of Algorithm 1 (Akinci et al. 2012) its own
//! way and ends with the same triangulation and normals. Layers, lowest first: `budget` (the
//! memory limit), `bricks/` (the band stored as 8³ bricks), `stages/` (the steps of Algorithm
//! 1), `engines/` (which run them).

pub(crate) mod bricks;
pub(crate) mod budget;
pub(crate) mod engines;
pub(crate) mod stages;

use glam::Vec3;

use crate::config::{Engine, Params};
use crate::error::Result;
use crate::mesh::TriMesh;
use crate::report::{FrameStats, Observer, Stages};
use engines::full_grid::{self, Grid};
use engines::{marching_slices, narrow_band, scatter, surface_following};

pub use engines::narrow_band::{Sampled, Sides};
pub use engines::prepared::Reconstruction;

/// Reconstructs the surface of `particles` with `params.engine`, in the current rayon pool.
#[cfg(test)]
pub(crate) fn reconstruct(
    particles: &[Vec3],
    params: &Params,
    observer: Option<&mut dyn Observer>,
) -> Result<Reconstruction> {
    reconstruct_along_flow(particles, None, None, params, observer)
}

/// The figures a frame's reconstruction starts from.
fn first_stats(particles: &[Vec3], params: &Params) -> FrameStats {
    FrameStats {
        spacing: params.spacing,
        cell: params.cell,
        particles: particles.len(),
        threads: rayon::current_num_threads(),
        ..FrameStats::default()
    }
}

/// The stages of a frame's reconstruction (with particles), and the grid of the full-grid
/// engines (the others report it without allocating it).
fn begin<'a>(
    particles: &[Vec3],
    params: &Params,
    observer: Option<&'a mut dyn Observer>,
) -> (Stages<'a>, Result<Grid>) {
    let mut stages = Stages::start(first_stats(particles, params), observer);
    let grid = Grid::around(particles, params.cell, params.support);
    if let Ok(g) = &grid {
        stages.stats.grid = g.resolution();
    }
    (stages, grid)
}

/// [`reconstruct`], with `sides` the field averaged along the flow with the frames beside
/// (`stages/flow_mean`; the narrow band and full gather engines, else ignored), from `own`,
/// frame t's field as [`sample`] sampled it, where given.
pub(crate) fn reconstruct_along_flow(
    particles: &[Vec3],
    own: Option<&Sampled>,
    sides: Option<&Sides<'_>>,
    params: &Params,
    observer: Option<&mut dyn Observer>,
) -> Result<Reconstruction> {
    if let Some(own) = own {
        let mut stages = Stages::start(own.stats, observer);
        stages.stats.threads = rayon::current_num_threads();
        return narrow_band::gather_along_flow(own, sides, particles, stages);
    }
    if particles.is_empty() {
        let stats = first_stats(particles, params);
        return Ok(Reconstruction::new(TriMesh::default(), stats));
    }
    let (mut stages, grid) = begin(particles, params, observer);
    if let Some(baseline) = params.baseline {
        return surface_following::reconstruct(particles, params, baseline, stages);
    }
    match params.engine {
        Engine::NarrowBand => narrow_band::gather(particles, params, stages),
        Engine::Slices => {
            marching_slices::reconstruct(particles, params, Default::default(), stages)
                .map(|(r, _)| r)
        }
        engine @ (Engine::FullGather | Engine::Scatter) => {
            let grid = grid?;
            stages.stats.planned_bytes =
                full_grid::check(params, &grid, particles.len())?.unwrap_or(0);
            if engine == Engine::Scatter {
                scatter::reconstruct(particles, params, &grid, stages)
            } else {
                narrow_band::gather(particles, params, stages)
            }
        }
    }
}

/// Frame t's field sampled on its closed band, for [`reconstruct_along_flow`] to make its
/// surface from and the frames beside it to average theirs with; None where the engine does
/// not sample so (the scatter, Marching Slices, the baselines) or there are no particles.
pub(crate) fn sample(
    particles: &[Vec3],
    params: &Params,
    observer: Option<&mut dyn Observer>,
) -> Result<Option<Sampled>> {
    let flows = matches!(params.engine, Engine::NarrowBand | Engine::FullGather);
    if particles.is_empty() || params.baseline.is_some() || !flows {
        return Ok(None);
    }
    let (mut stages, grid) = begin(particles, params, observer);
    if params.engine == Engine::FullGather {
        stages.stats.planned_bytes =
            full_grid::check(params, &grid?, particles.len())?.unwrap_or(0);
    }
    narrow_band::sample(particles, params, &mut stages).map(Some)
}
