//! The reconstructor of Akinci et al. 2012, Algorithm 1: surface particles, the band of surface
//! vertices around them, the handler array for the gather, the scalar field on the band, and
//! the triangulation of the surface cells.

use anyhow::Result;
use glam::Vec3;

use super::band::{BRICK_VERTICES, Band};
use super::band_closure::close_band;
use super::field_sampling::{BrickValues, sample_field};
use super::full_grid::{self, Grid};
use super::handler_array::HandlerArray;
use super::marching_slices::{self, Checks};
use super::normals::set_normals;
use super::scatter;
use super::surface_particles::{SurfaceCriteria, surface_particles};
use super::triangulation::{Triangulation, triangulate};
use crate::config::Params;
use crate::field::{Fitted, ScalarField};
use crate::memory;
use crate::mesh::TriMesh;
use crate::report::{FrameStats, Stage, Stages};

/// Which grid vertices get a field value.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Engine {
    /// Only the band around the surface particles (Sec. 4.1).
    NarrowBand,
    /// Every vertex of the particles' bounding box widened by the support: the paper's
    /// "Z-index" gather without a narrow band. Memory follows the volume.
    FullGather,
    /// Serial scatter of every particle into per-vertex sums over the same full grid, then all
    /// cells triangulated: the paper's "scatter" row (SSP07 only; see `scatter.rs`).
    Scatter,
    /// Block-parallel Marching Slices (Rosenberg & Birdwell 2008; see `marching_slices`).
    Slices,
}

/// Resource limits of one reconstruction.
#[derive(Debug, Clone, Copy)]
pub struct Limits {
    /// Largest heap, in bytes, that a full-grid engine may plan to use (`--max-memory`).
    pub max_memory: u64,
}

impl Default for Limits {
    /// Half the machine's memory.
    fn default() -> Self {
        Limits {
            max_memory: memory::default_limit(),
        }
    }
}

pub struct Reconstruction {
    pub mesh: TriMesh,
    pub stats: FrameStats,
}

pub fn reconstruct(particles: &[Vec3], params: &Params, engine: Engine) -> Result<Reconstruction> {
    reconstruct_with(particles, params, engine, &Limits::default())
}

pub fn reconstruct_with(
    particles: &[Vec3],
    params: &Params,
    engine: Engine,
    limits: &Limits,
) -> Result<Reconstruction> {
    let mut stages = Stages::start(FrameStats {
        spacing: params.spacing,
        cell: params.cell,
        particles: particles.len(),
        threads: rayon::current_num_threads(),
        ..FrameStats::default()
    });
    if particles.is_empty() {
        return Ok(Reconstruction {
            mesh: TriMesh::default(),
            stats: stages.stats,
        });
    }
    // The grid of the full-grid engines; the narrow band reports it without allocating it.
    let grid = Grid::around(particles, params.cell, params.support);
    if engine.is_full_grid() {
        let grid = grid.as_ref().map_err(|e| anyhow::anyhow!("{e:#}"))?;
        full_grid::check(engine, grid, particles.len(), limits.max_memory)?;
    }
    if let Ok(g) = &grid {
        stages.stats.grid = g.resolution();
    }
    match engine {
        Engine::Scatter => scatter::reconstruct(particles, params, &grid?, stages),
        Engine::NarrowBand | Engine::FullGather => gather(particles, params, engine, stages),
        Engine::Slices => {
            marching_slices::reconstruct(particles, params, Checks::default(), stages)
                .map(|(r, _)| r)
        }
    }
}

/// Algorithm 1; with [`Engine::FullGather`], the same gather on every vertex of the grid.
fn gather(
    particles: &[Vec3],
    params: &Params,
    engine: Engine,
    mut stages: Stages,
) -> Result<Reconstruction> {
    let prepared = prepare(particles, params, &mut stages)?;
    let (field, samples) = prepared.sampling();
    // The full grid reaches as far as the fitted kernels do.
    let params = &Params {
        support: field.support(),
        ..params.clone()
    };
    let mut band = if engine == Engine::NarrowBand {
        let surface = stages.run(Stage::SurfaceParticles, || {
            surface_particles(&prepared.handlers, &SurfaceCriteria::of(params))
        });
        stages.stats.surface_particles = surface.len();
        stages.run(Stage::Band, || {
            Band::around(&surface, params.cell, params.band_half_width)
        })?
    } else {
        stages.run(Stage::Band, || full_grid::band(particles, params))?
    };
    let mut values = stages.run(Stage::ScalarField, || sample_field(&band, samples, field));
    stages.stats.closure_vertices = stages.run(Stage::Band, || {
        close_band(&mut band, &mut values, |grown| {
            sample_field(grown, samples, field)
        })
    });
    let triangulation = stages.run(Stage::Triangulation, || -> Result<_> {
        let mut t = triangulate(&band, &values);
        let cell = band.cell;
        set_normals(
            params.normals,
            &mut t.mesh,
            &t.brick_vertices,
            cell,
            || Ok(samples),
            field,
        )?;
        Ok(t)
    })?;
    Ok(finish(
        stages.stats,
        &band,
        &values,
        prepared.heap_bytes(),
        triangulation,
    ))
}

/// The field, and the handler array of the frame with the field's channels; fields with
/// adaptive kernels also come fitted to the frame, with their own handler array.
pub(super) struct Prepared {
    field: Box<dyn ScalarField>,
    pub handlers: HandlerArray,
    fitted: Option<Fitted>,
}

impl Prepared {
    /// The field to sample and the handler array to gather its particles from.
    pub fn sampling(&self) -> (&dyn ScalarField, &HandlerArray) {
        match &self.fitted {
            Some(f) => (f.field.as_ref(), &f.handlers),
            None => (self.field.as_ref(), &self.handlers),
        }
    }

    pub fn heap_bytes(&self) -> usize {
        self.handlers.heap_bytes() + self.fitted.as_ref().map_or(0, |f| f.handlers.heap_bytes())
    }
}

pub(super) fn prepare(
    particles: &[Vec3],
    params: &Params,
    stages: &mut Stages,
) -> Result<Prepared> {
    let field = params.field.build(params.spacing);
    // The handler array comes first here, as the colour field needs the neighbours too.
    let mut handlers = stages.run(Stage::HandlerArray, || {
        HandlerArray::new(particles, lookup_cell(params))
    })?;
    // Per-particle work, like the colour field: counted with t_sp.
    handlers.channels = stages.run(Stage::SurfaceParticles, || {
        field.particle_channels(&handlers)
    });
    let fitted = stages
        .run(Stage::ScalarField, || field.fit(&handlers))
        .transpose()?;
    Ok(Prepared {
        field,
        handlers,
        fitted,
    })
}

/// Lookup cells that suit both gathers: the colour support (2r), and half the field's support
/// (2r for SSP07) so that a brick's reach spans few cells.
fn lookup_cell(params: &Params) -> f32 {
    params.colour_support.max(params.support / 2.0)
}

/// Counts and memory figures once the mesh exists.
pub(super) fn finish(
    mut stats: FrameStats,
    band: &Band,
    values: &BrickValues,
    handler_bytes: usize,
    triangulation: Triangulation,
) -> Reconstruction {
    let values_bytes = values.capacity() * BRICK_VERTICES * size_of::<f32>();
    let mesh = triangulation.mesh;
    stats.bricks = band.bricks.len();
    stats.surface_vertices = band.surface_vertices();
    stats.surface_cells = triangulation.surface_cells;
    stats.triangles = mesh.triangles.len();
    stats.vertices = mesh.vertices.len();
    stats.peak_bytes = handler_bytes + band.heap_bytes() + values_bytes + mesh.heap_bytes();
    stats.heap_peak = stats.stage_heap.max();
    stats.peak_rss = memory::peak_rss().unwrap_or(0);
    Reconstruction { mesh, stats }
}
