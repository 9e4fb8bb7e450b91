//! Surface reconstruction engines behind one signature: [`reconstruct`] runs the engine that
//! the parameters name. Each engine runs the stages of Algorithm 1 (Akinci et al. 2012) its own
//! way and ends with the same triangulation and normals.

pub(crate) mod band;
pub(crate) mod band_closure;
pub(crate) mod brick_neighbours;
pub(crate) mod brick_signs;
pub(crate) mod brick_values;
pub(crate) mod budget;
pub(crate) mod deferred_values;
pub(crate) mod edge_tables;
pub(crate) mod field_sampling;
pub(crate) mod full_grid;
pub(crate) mod halo;
pub(crate) mod lone_particles;
pub(crate) mod marching_slices;
pub(crate) mod narrow_band;
pub(crate) mod normals;
pub(crate) mod prepared;
pub(crate) mod scatter;
pub(crate) mod surface_cells;
pub(crate) mod surface_particles;
pub(crate) mod triangulation;
pub(crate) mod vertex_correction;

use glam::Vec3;

use crate::config::{Engine, Params};
use crate::error::Result;
use crate::mesh::TriMesh;
use crate::report::{FrameStats, Observer, Stages};
use full_grid::Grid;

/// A mesh and the report of its reconstruction.
#[derive(Debug, Clone, Default)]
pub struct Reconstruction {
    /// The closed, outward-oriented surface.
    pub mesh: TriMesh,
    /// Counts, array bytes, and the stage figures of an [`Observer`](crate::Observer).
    pub stats: FrameStats,
}

/// Reconstructs the surface of `particles` with `params.engine`, in the current rayon pool.
pub(crate) fn reconstruct(
    particles: &[Vec3],
    params: &Params,
    observer: Option<&mut dyn Observer>,
) -> Result<Reconstruction> {
    let mut stages = Stages::start(
        FrameStats {
            spacing: params.spacing,
            cell: params.cell,
            particles: particles.len(),
            threads: rayon::current_num_threads(),
            ..FrameStats::default()
        },
        observer,
    );
    if particles.is_empty() {
        return Ok(Reconstruction {
            mesh: TriMesh::default(),
            stats: stages.stats,
        });
    }
    // The grid of the full-grid engines; the others report it without allocating it.
    let grid = Grid::around(particles, params.cell, params.support);
    if let Ok(g) = &grid {
        stages.stats.grid = g.resolution();
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
