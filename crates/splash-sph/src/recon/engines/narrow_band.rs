//! The reconstructor of Akinci et al. 2012, Algorithm 1: surface particles, the band of surface
//! vertices around them, the handler array for the gather, the scalar field on the band, and
//! the triangulation of the surface cells.

use glam::Vec3;

use super::full_grid;
use super::prepared::Reconstruction;
use super::prepared::{finish, prepare, triangles_and_normals};
use crate::config::{Engine, Params};
use crate::error::Result;
use crate::recon::bricks::band::Band;
use crate::recon::budget::{self, PER_BRICK, mul};
use crate::recon::stages::band_closure::close_band;
use crate::recon::stages::deferred_values::Deferred;
use crate::recon::stages::field_sampling::sample_field;
use crate::recon::stages::lone_particles::band_half_widths;
use crate::recon::stages::surface_particles::{SurfaceCriteria, surface_particles};
use crate::recon::stages::triangulation::triangulate;
use crate::report::{Stage, Stages};

/// Algorithm 1; with [`Engine::FullGather`], the same gather on every vertex of the grid.
pub(crate) fn gather(
    particles: &[Vec3],
    params: &Params,
    mut stages: Stages,
) -> Result<Reconstruction> {
    let prepared = prepare(particles, params, &mut stages)?;
    let (field, samples) = prepared.sampling();
    // The full grid reaches as far as the fitted kernels do.
    let params = &Params {
        support: field.support(),
        ..params.clone()
    };
    let held = prepared.heap_bytes() as u64;
    // The mesh is estimated from the surface particles; the full gather has none, and its
    // estimate was checked on the grid before it started.
    let mut surface_count = None;
    let mut band = if params.engine == Engine::NarrowBand {
        let surface = stages.run(Stage::SurfaceParticles, || {
            surface_particles(&prepared.handlers, &SurfaceCriteria::of(params))
        });
        stages.stats.surface_particles = surface.len();
        surface_count = Some(surface.len() as u64);
        let n = surface.len();
        stages.run(Stage::Band, || {
            let widths = band_half_widths(&surface, &prepared.handlers, field, params)?;
            Band::around_within(&surface, params.cell, &widths, |pairs| {
                // The pairs, twice while gathered, beside the particles' boxes.
                let need = held
                    .saturating_add(mul(pairs, 32))
                    .saturating_add(mul(n as u64, 36));
                budget::check(params, need, || {
                    format!(
                        "the band around {n} surface particles ({pairs} pairs of a brick of \
                         8³ cells and a particle reaching it)"
                    )
                })
                .map(drop)
            })
        })?
    } else {
        stages.run(Stage::Band, || full_grid::band(particles, params))?
    };
    let surface = surface_count.unwrap_or_else(|| budget::surface_guess(particles.len()));
    let mesh = budget::mesh_bytes(budget::mesh_vertices(params, surface));
    // The band's bricks, their values and the mesh, before the values are sampled.
    let need_for = |bricks: usize| {
        held.saturating_add(mul(bricks as u64, PER_BRICK))
            .saturating_add(mesh)
    };
    let bricks_what = |bricks: usize| {
        move || {
            format!(
                "the field values of a band of {bricks} bricks of 8³ vertices and a mesh of \
                 about {} vertices",
                budget::mesh_vertices(params, surface)
            )
        }
    };
    let planned = budget::check(
        params,
        need_for(band.bricks.len()),
        bricks_what(band.bricks.len()),
    )?;
    if params.engine == Engine::NarrowBand {
        stages.stats.planned_bytes = planned;
    }
    let (mut values, deferred) = stages.run(Stage::ScalarField, || {
        Deferred::sample(&band, samples, field)
    })?;
    stages.stats.deferred_values = deferred.len();
    let closed = stages.run(Stage::Band, || {
        close_band(&mut band, &mut values, |grown, bricks| {
            budget::check(params, need_for(bricks), bricks_what(bricks))?;
            sample_field(grown, samples, field)
        })
    })?;
    stages.stats.closure_vertices = closed.added;
    stages.stats.deferred_values -= stages.run(Stage::ScalarField, || {
        deferred.resolve(&band, &mut values, &closed.tables, samples, field)
    })?;
    let held = held + (band.heap_bytes() + values.heap_bytes()) as u64;
    let triangulation = triangles_and_normals(
        &mut stages,
        params,
        field,
        || {
            triangulate(&band, &values, closed.signs, closed.tables, |mesh| {
                budget::check(params, held.saturating_add(mesh), || {
                    "the mesh of the band's surface".into()
                })
                .map(drop)
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
