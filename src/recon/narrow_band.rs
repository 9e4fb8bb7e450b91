//! The reconstructor of Akinci et al. 2012, Algorithm 1: surface particles, the band of surface
//! vertices around them, the handler array for the gather, the scalar field on the band, and
//! the triangulation of the surface cells.

use anyhow::{Result, bail};
use glam::Vec3;

use super::band::{BRICK_VERTICES, Band};
use super::band_closure::close_band;
use super::field_sampling::sample_field;
use super::full_grid::{self, Grid};
use super::handler_array::HandlerArray;
use super::scatter::scatter_field;
use super::surface_particles::{SurfaceCriteria, surface_particles};
use super::triangulation::{Triangulation, triangulate};
use crate::config::Params;
use crate::field::FieldConfig;
use crate::field::density::particle_volumes;
use crate::memory::{self, HeapScope};
use crate::mesh::TriMesh;
use crate::report::{FrameStats, staged};

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
    let heap = HeapScope::start();
    let mut stats = FrameStats {
        spacing: params.spacing,
        cell: params.cell,
        particles: particles.len(),
        threads: rayon::current_num_threads(),
        ..FrameStats::default()
    };
    if particles.is_empty() {
        return Ok(Reconstruction {
            mesh: TriMesh::default(),
            stats,
        });
    }
    // The grid of the full-grid engines; the narrow band reports it without allocating it.
    let grid = Grid::around(particles, params.cell, params.support);
    if engine.is_full_grid() {
        let grid = grid.as_ref().map_err(|e| anyhow::anyhow!("{e:#}"))?;
        full_grid::check(engine, grid, particles.len(), limits.max_memory)?;
    }
    if let Ok(g) = &grid {
        stats.grid = g.resolution();
    }
    let t = &mut stats.timings;
    let h = &mut stats.stage_heap;
    let field = params.field.build(params.spacing);
    let field = field.as_ref();
    // The handler array comes first here: the colour field needs the neighbours too. Its cells
    // suit both gathers: the colour support (2r), and half the field's support (2r) so that a
    // brick's reach spans few cells.
    if engine == Engine::Scatter {
        // Only SSP07's value is a function of sums a particle can add to, so far.
        let FieldConfig::Ssp07(ssp07) = &params.field else {
            bail!(
                "the scatter engine supports the ssp07 field only, not {}: use the narrow-band or full-gather engine",
                params.field.kind()
            );
        };
        let field = ssp07.resolve(params.spacing);
        // No handler array: the scatter needs no neighbour search.
        let grid = grid?;
        let (lo, hi) = full_grid::bounds(particles);
        let band = staged(&mut t.band, &mut h.band, &heap, || {
            Band::full(lo, hi, params.cell, params.support)
        })?;
        let values = staged(&mut t.scalar_field, &mut h.scalar_field, &heap, || {
            scatter_field(particles, &band, &grid, &field)
        })?;
        let triangulation = staged(&mut t.triangulation, &mut h.triangulation, &heap, || {
            triangulate(&band, &values)
        });
        let values_bytes = values.capacity() * BRICK_VERTICES * size_of::<f32>();
        return Ok(finish(stats, &band, values_bytes, 0, triangulation));
    }
    let lookup_cell = params.colour_support.max(params.support / 2.0);
    let mut handlers = staged(&mut t.handler_array, &mut h.handler_array, &heap, || {
        HandlerArray::new(particles, lookup_cell)
    })?;
    if let Some(support) = field.particle_volume_support() {
        // Per-particle work, like the colour field: counted with t_sp.
        handlers.volumes = staged(
            &mut t.surface_particles,
            &mut h.surface_particles,
            &heap,
            || particle_volumes(&handlers, support),
        );
    }
    let band = match engine {
        Engine::NarrowBand => {
            let criteria = SurfaceCriteria {
                support: params.colour_support,
                volume: params.spacing.powi(3),
                colour_threshold: params.colour_threshold,
                min_neighbours: params.min_neighbours,
            };
            let surface = staged(
                &mut t.surface_particles,
                &mut h.surface_particles,
                &heap,
                || surface_particles(&handlers, &criteria),
            );
            stats.surface_particles = surface.len();
            staged(&mut t.band, &mut h.band, &heap, || {
                Band::around(&surface, params.cell, params.band_half_width)
            })?
        }
        Engine::FullGather | Engine::Scatter => {
            let (lo, hi) = full_grid::bounds(particles);
            staged(&mut t.band, &mut h.band, &heap, || {
                Band::full(lo, hi, params.cell, params.support)
            })?
        }
    };
    let mut band = band;
    let mut values = staged(&mut t.scalar_field, &mut h.scalar_field, &heap, || {
        sample_field(&band, &handlers, field)
    });
    stats.closure_vertices = staged(&mut t.band, &mut h.band, &heap, || {
        close_band(&mut band, &mut values, |grown| {
            sample_field(grown, &handlers, field)
        })
    });
    let values_bytes = values.capacity() * BRICK_VERTICES * size_of::<f32>();
    let triangulation = staged(&mut t.triangulation, &mut h.triangulation, &heap, || {
        triangulate(&band, &values)
    });
    Ok(finish(
        stats,
        &band,
        values_bytes,
        handlers.heap_bytes(),
        triangulation,
    ))
}

/// Counts and memory figures once the mesh exists.
fn finish(
    mut stats: FrameStats,
    band: &Band,
    values_bytes: usize,
    handler_bytes: usize,
    triangulation: Triangulation,
) -> Reconstruction {
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
