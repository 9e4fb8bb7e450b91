//! The reconstructor of Akinci et al. 2012, Algorithm 1: surface particles, the band of surface
//! vertices around them, the handler array for the gather, the scalar field on the band, and
//! the triangulation of the surface cells.

use glam::Vec3;

use super::Reconstruction;
use super::band::Band;
use super::band_closure::close_band;
use super::field_sampling::sample_field;
use super::full_grid;
use super::prepared::{finish, prepare, triangles_and_normals};
use super::surface_particles::{SurfaceCriteria, surface_particles};
use super::triangulation::triangulate;
use crate::config::{Engine, Params};
use crate::error::Result;
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
    let mut band = if params.engine == Engine::NarrowBand {
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
    let triangulation = triangles_and_normals(
        &mut stages,
        params,
        field,
        || triangulate(&band, &values),
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
