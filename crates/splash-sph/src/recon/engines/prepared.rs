//! What every engine shares: the field and the handler array of the frame before the field is
//! sampled, and the counts and memory figures once the mesh exists, in the [`Reconstruction`]
//! every engine returns.

use std::borrow::Borrow;
use std::sync::Arc;

use glam::Vec3;

use crate::config::Params;
use crate::error::Result;
use crate::field::{Fitted, ScalarField};
use crate::mesh::TriMesh;
use crate::neighbours::handler_array::HandlerArray;
use crate::recon::bricks::band::Band;
use crate::recon::bricks::brick_values::BrickValues;
use crate::recon::budget::{self, PER_PARTICLE, mul};
use crate::recon::stages::normals::set_normals;
use crate::recon::stages::surface_particles::{
    SurfaceCriteria, surface_particles, surface_particles_and_volumes,
};
use crate::recon::stages::triangulation::Triangulation;
use crate::recon::stages::vertex_correction::correct_vertices;
use crate::report::{CorrectionFigures, FrameStats, Stage, Stages};

/// A mesh and the report of its reconstruction.
#[derive(Debug, Clone, Default)]
pub struct Reconstruction {
    /// The closed, outward-oriented surface.
    pub mesh: TriMesh,
    /// Counts, array bytes, and the stage figures of an [`Observer`](crate::Observer).
    pub stats: FrameStats,
    /// Per vertex, whether the post-processing found another side of the surface facing it
    /// within its clearance's reach; empty where it did not look.
    pub(crate) close: Vec<bool>,
}

impl Reconstruction {
    /// An engine's surface with its figures; only the post-processing knows which vertices
    /// are close.
    pub(crate) fn new(mesh: TriMesh, stats: FrameStats) -> Reconstruction {
        Reconstruction {
            mesh,
            stats,
            close: Vec::new(),
        }
    }
}

/// The field, and the handler array of the frame with the field's channels; fields with
/// adaptive kernels also come fitted to the frame, with their own handler array.
pub(super) struct Prepared {
    field: Arc<dyn ScalarField>,
    pub handlers: HandlerArray,
    fitted: Option<Fitted>,
    /// The surface particles, where [`prepare`] was asked for them.
    pub surface: Option<Vec<Vec3>>,
}

impl Prepared {
    /// The field to sample and the handler array to gather its particles from.
    pub fn sampling(&self) -> (&dyn ScalarField, &HandlerArray) {
        match &self.fitted {
            Some(f) => (f.field.as_ref(), &f.handlers),
            None => (self.field.as_ref(), &self.handlers),
        }
    }

    /// Whether the field comes fitted to the frame (the anisotropic field).
    pub fn is_fitted(&self) -> bool {
        self.fitted.is_some()
    }

    pub fn heap_bytes(&self) -> usize {
        self.handlers.heap_bytes() + self.fitted.as_ref().map_or(0, |f| f.handlers.heap_bytes())
    }
}

/// The handler array of `particles` with the field's channels, and with `surface` criteria
/// the surface particles too: from the same pass as the density field's volumes where their
/// supports agree.
pub(super) fn prepare(
    particles: &[Vec3],
    params: &Params,
    stages: &mut Stages<'_>,
    surface: Option<&SurfaceCriteria>,
) -> Result<Prepared> {
    let field = Arc::clone(&params.field);
    let n = particles.len();
    budget::check(params, mul(n as u64, PER_PARTICLE), || {
        format!("the handler array of {n} particles")
    })?;
    // The handler array comes first here, as the colour field needs the neighbours too.
    let mut handlers = stages.run(Stage::HandlerArray, || {
        HandlerArray::new(particles, lookup_cell(params))
    })?;
    // Per-particle work, like the colour field: counted with t_sp.
    let (channels, surface) = stages.run(Stage::SurfaceParticles, || match surface {
        Some(criteria) if field.volume_support() == Some(criteria.support) => {
            let (surface, volumes) = surface_particles_and_volumes(&handlers, criteria);
            (vec![volumes], Some(surface))
        }
        Some(criteria) => (
            field.particle_channels(&handlers),
            Some(surface_particles(&handlers, criteria)),
        ),
        None => (field.particle_channels(&handlers), None),
    });
    handlers.channels = channels;
    let fitted = stages
        .run(Stage::ScalarField, || field.fit(&handlers))
        .transpose()?;
    Ok(Prepared {
        field,
        handlers,
        fitted,
        surface,
    })
}

/// Lookup cells that suit both gathers: the colour support (2r), and half the field's support
/// (2r for SSP07) so that a brick's reach spans few cells.
fn lookup_cell(params: &Params) -> f32 {
    params.colour_support.max(params.support / 2.0)
}

/// The last stage of every engine, timed as t_tri: the triangles, their vertices corrected
/// when `params.correct` asks for it, then the vertex normals that `params.normals` asks for
/// (only the correction and the field's normals gather particles: `handlers`).
pub(super) fn triangles_and_normals<H: Borrow<HandlerArray>>(
    stages: &mut Stages<'_>,
    params: &Params,
    field: &dyn ScalarField,
    triangles: impl FnOnce() -> Result<Triangulation>,
    handlers: impl FnOnce() -> Result<H>,
) -> Result<Triangulation> {
    let mut figures = CorrectionFigures::default();
    let t = stages.run(Stage::Triangulation, || {
        let mut t = triangles()?;
        let (mesh, bricks) = (&mut t.mesh, &t.brick_vertices);
        if params.correct == 0 {
            set_normals(params.normals, mesh, bricks, params.cell, handlers, field)?;
            return Ok(t);
        }
        let h = handlers()?;
        let h = h.borrow();
        figures = correct_vertices(mesh, bricks, params.cell, h, field, params.correct);
        set_normals(params.normals, mesh, bricks, params.cell, || Ok(h), field)?;
        Ok(t)
    })?;
    stages.stats.correction = figures;
    Ok(t)
}

/// Counts and memory figures once the mesh exists.
pub(super) fn finish(
    mut stats: FrameStats,
    band: &Band,
    values: &BrickValues,
    handler_bytes: usize,
    triangulation: Triangulation,
) -> Reconstruction {
    let values_bytes = values.heap_bytes();
    let mesh = triangulation.mesh;
    stats.bricks = band.bricks.len();
    stats.surface_vertices = band.surface_vertices();
    stats.surface_cells = triangulation.surface_cells;
    stats.triangles = mesh.triangles.len();
    stats.vertices = mesh.vertices.len();
    stats.peak_bytes = handler_bytes + band.heap_bytes() + values_bytes + mesh.heap_bytes();
    stats.heap_peak = stats.stage_heap.max();
    Reconstruction::new(mesh, stats)
}
