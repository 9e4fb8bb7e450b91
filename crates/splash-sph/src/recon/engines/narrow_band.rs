//! The reconstructor of Akinci et al. 2012, Algorithm 1: surface particles, the band of surface
//! vertices around them, the handler array for the gather, the scalar field on the band, and
//! the triangulation of the surface cells.

use glam::Vec3;

use super::full_grid;
use super::prepared::{Reconstruction, finish, prepare, triangles_and_normals};
use crate::config::{Engine, Params};
use crate::error::Result;
use crate::field::ScalarField;
use crate::neighbours::handler_array::HandlerArray;
use crate::recon::bricks::band::Band;
use crate::recon::bricks::brick_values::BrickValues;
use crate::recon::budget::{self, PER_BRICK, PER_PARTICLE, mul};
use crate::recon::stages::band_closure::close_band;
use crate::recon::stages::deferred_values::Deferred;
use crate::recon::stages::field_sampling::sample_field;
use crate::recon::stages::flow_mean::{FlowMean, Sides};
use crate::recon::stages::lone_particles::band_half_widths;
use crate::recon::stages::surface_particles::SurfaceCriteria;
use crate::recon::stages::triangulation::triangulate;
use crate::report::{Stage, Stages};

/// Algorithm 1; with [`Engine::FullGather`], the same gather on every vertex of the grid.
pub(crate) fn gather(
    particles: &[Vec3],
    sides: Option<&Sides<'_>>,
    params: &Params,
    mut stages: Stages,
) -> Result<Reconstruction> {
    let criteria = SurfaceCriteria::of(params);
    let narrow = params.engine == Engine::NarrowBand;
    let mut prepared = prepare(particles, params, &mut stages, narrow.then_some(&criteria))?;
    let surface = prepared.surface.take();
    let (field, samples) = prepared.sampling();
    // The full grid reaches as far as the fitted kernels do.
    let params = &Params {
        support: field.support(),
        ..params.clone()
    };
    let held = prepared.heap_bytes() as u64;
    let (mut band, limits) = if let Some(surface) = surface {
        stages.stats.surface_particles = surface.len();
        let band = stages.run(Stage::Band, || {
            band_around(&surface, &prepared.handlers, field, params, held)
        })?;
        (band, Limits::new(params, held, surface.len() as u64))
    } else {
        // The full gather has no surface particles; its estimate was checked on the grid.
        let band = stages.run(Stage::Band, || full_grid::band(particles, params))?;
        let surface = budget::surface_guess(particles.len());
        (band, Limits::new(params, held, surface))
    };
    let planned = limits.band(band.bricks.len())?;
    if params.engine == Engine::NarrowBand {
        stages.stats.planned_bytes = planned;
    }
    // A field fitted to frame t's particles does not hold for its neighbours'.
    let flow = sides
        .filter(|_| !prepared.is_fitted())
        .map(|s| {
            let n = (particles.len() + s.particles.iter().map(|p| p.len()).sum::<usize>()) as u64;
            // Three handler arrays, frame t's with eight channels more.
            let need = held
                .saturating_add(mul(n, PER_PARTICLE))
                .saturating_add(mul(particles.len() as u64, 32));
            budget::check(params, need, || {
                format!("the particles of three frames ({n}) to average the field along the flow")
            })?;
            stages.run(Stage::ScalarField, || {
                let lookup = prepared.handlers.cell_size();
                FlowMean::new(particles, s, field, params.spacing, lookup)
            })
        })
        .transpose()?;
    let held = held + flow.as_ref().map_or(0, |f| f.heap_bytes() as u64);
    let (mut values, mut deferred) = stages.run(Stage::ScalarField, || {
        Deferred::sample(&band, samples, field)
    })?;
    stages.stats.deferred_values = deferred.len();
    let mut added = 0;
    let mut close = |band: &mut Band, values: &mut BrickValues| {
        let closed = close_band(band, values, |grown, bricks| {
            limits.band(bricks)?;
            sample_field(grown, samples, field)
        })?;
        added += closed.added;
        Ok(closed)
    };
    let mut closed = stages.run(Stage::Band, || close(&mut band, &mut values))?;
    let mut resolved = stages.run(Stage::ScalarField, || {
        deferred.resolve(&band, &mut values, &closed.tables, samples, field)
    })?;
    if let Some(flow) = &flow {
        // Every crossed edge's ends hold frame t's own values before they are averaged.
        stages.stats.flow_mean_vertices = stages.run(Stage::ScalarField, || {
            flow.average_crossed(
                &mut band,
                &mut values,
                &mut closed,
                field,
                |band, values| {
                    let closed = close(band, values)?;
                    resolved += deferred.resolve(band, values, &closed.tables, samples, field)?;
                    Ok(closed)
                },
            )
        })?;
    }
    stages.stats.closure_vertices = added;
    stages.stats.deferred_values -= resolved;
    let held = held + (band.heap_bytes() + values.heap_bytes()) as u64;
    let triangulation = triangles_and_normals(
        &mut stages,
        params,
        field,
        || {
            triangulate(&band, &values, closed.signs, closed.tables, |mesh| {
                limits.mesh(held, mesh)
            })
        },
        || Ok(samples),
    )?;
    Ok(finish(
        stages.stats,
        &band,
        &values,
        prepared.heap_bytes(),
        triangulation,
    ))
}

/// The band of surface vertices around the surface particles (Sec. 4.1), each particle's box
/// as wide as [`band_half_widths`] gives, checked against `max_memory` before the (brick,
/// particle) pairs that build it are gathered.
fn band_around(
    surface: &[Vec3],
    handlers: &HandlerArray,
    field: &dyn ScalarField,
    params: &Params,
    held: u64,
) -> Result<Band> {
    let widths = band_half_widths(surface, handlers, field, params)?;
    let n = surface.len();
    Band::around_within(surface, params.cell, &widths, |pairs| {
        // The pairs, twice while gathered, beside the particles' boxes.
        let need = held
            .saturating_add(mul(pairs, 32))
            .saturating_add(mul(n as u64, 36));
        budget::check(params, need, || {
            format!(
                "the band around {n} surface particles ({pairs} pairs of a brick of 8³ cells \
                 and a particle reaching it)"
            )
        })
        .map(drop)
    })
}

/// The `max_memory` checks of the gather after the band: `held` bytes of the frame, and a mesh
/// estimated from the surface particles (or a guess at them, for the full gather).
struct Limits<'a> {
    params: &'a Params,
    held: u64,
    mesh_vertices: u64,
}

impl<'a> Limits<'a> {
    fn new(params: &'a Params, held: u64, surface: u64) -> Self {
        Limits {
            params,
            held,
            mesh_vertices: budget::mesh_vertices(params, surface),
        }
    }

    /// A band of `bricks` bricks with their values, and the mesh: the bytes planned.
    fn band(&self, bricks: usize) -> Result<u64> {
        let need = self
            .held
            .saturating_add(mul(bricks as u64, PER_BRICK))
            .saturating_add(budget::mesh_bytes(self.mesh_vertices));
        budget::check(self.params, need, || {
            format!(
                "the field values of a band of {bricks} bricks of 8³ vertices and a mesh of \
                 about {} vertices",
                self.mesh_vertices
            )
        })
    }

    /// The mesh of `mesh` bytes beside `held` bytes of the frame and its band.
    fn mesh(&self, held: u64, mesh: u64) -> Result<()> {
        budget::check(self.params, held.saturating_add(mesh), || {
            "the mesh of the band's surface".into()
        })
        .map(drop)
    }
}
