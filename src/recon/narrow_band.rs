//! The reconstructor of Akinci et al. 2012, Algorithm 1: surface particles, the band of surface
//! vertices around them, the handler array for the gather, the scalar field on the band, and
//! the triangulation of the surface cells.

use anyhow::Result;
use glam::Vec3;

use super::band::{BRICK_VERTICES, Band};
use super::band_closure::close_band;
use super::field_sampling::sample_field;
use super::handler_array::HandlerArray;
use super::surface_particles::{SurfaceCriteria, surface_particles};
use super::triangulation::triangulate;
use crate::config::Params;
use crate::field::density::particle_volumes;
use crate::mesh::TriMesh;
use crate::report::{FrameStats, timed};

/// Which grid vertices get a field value.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Engine {
    /// Only the band around the surface particles (Sec. 4.1).
    NarrowBand,
    /// Every vertex of the particles' bounding box widened by the support: the paper's
    /// "Z-index" gather without a narrow band. Memory follows the volume.
    FullGather,
}

pub struct Reconstruction {
    pub mesh: TriMesh,
    pub stats: FrameStats,
}

pub fn reconstruct(particles: &[Vec3], params: &Params, engine: Engine) -> Result<Reconstruction> {
    let mut stats = FrameStats {
        particles: particles.len(),
        ..FrameStats::default()
    };
    if particles.is_empty() {
        return Ok(Reconstruction {
            mesh: TriMesh::default(),
            stats,
        });
    }
    let t = &mut stats.timings;
    let field = params.field.build(params.spacing);
    let field = field.as_ref();
    // The handler array comes first here: the colour field needs the neighbours too. Its cells
    // suit both gathers: the colour support (2r), and half the field's support (2r) so that a
    // brick's reach spans few cells.
    let lookup_cell = params.colour_support.max(params.support / 2.0);
    let mut handlers = timed(&mut t.handler_array, || {
        HandlerArray::new(particles, lookup_cell)
    })?;
    if let Some(support) = field.particle_volume_support() {
        // Per-particle work, like the colour field: counted with t_sp.
        handlers.volumes = timed(&mut t.surface_particles, || {
            particle_volumes(&handlers, support)
        });
    }
    let band = match engine {
        Engine::NarrowBand => {
            let criteria = SurfaceCriteria {
                support: params.colour_support,
                volume: params.spacing.powi(3),
                colour_threshold: params.colour_threshold,
                min_neighbours: params.min_neighbours,
            };
            let surface = timed(&mut t.surface_particles, || {
                surface_particles(&handlers, &criteria)
            });
            stats.surface_particles = surface.len();
            timed(&mut t.band, || {
                Band::around(&surface, params.cell, params.band_half_width)
            })?
        }
        Engine::FullGather => {
            let (lo, hi) = bounds(particles);
            timed(&mut t.band, || {
                Band::full(lo, hi, params.cell, params.support)
            })?
        }
    };
    let mut band = band;
    let mut values = timed(&mut t.scalar_field, || {
        sample_field(&band, &handlers, field)
    });
    stats.closure_vertices = timed(&mut t.band, || {
        close_band(&mut band, &mut values, |grown| {
            sample_field(grown, &handlers, field)
        })
    });
    let values_bytes = values.capacity() * BRICK_VERTICES * size_of::<f32>();
    let held_before_mesh = handlers.heap_bytes() + band.heap_bytes() + values_bytes;
    let triangulation = timed(&mut t.triangulation, || triangulate(&band, &values));
    let mesh = triangulation.mesh;
    stats.bricks = band.bricks.len();
    stats.surface_vertices = band.surface_vertices();
    stats.surface_cells = triangulation.surface_cells;
    stats.triangles = mesh.triangles.len();
    stats.vertices = mesh.vertices.len();
    stats.peak_bytes = held_before_mesh + mesh.heap_bytes();
    Ok(Reconstruction { mesh, stats })
}

fn bounds(particles: &[Vec3]) -> (Vec3, Vec3) {
    particles
        .iter()
        .fold((Vec3::MAX, Vec3::MIN), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        })
}
