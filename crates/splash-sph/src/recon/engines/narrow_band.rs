//! The reconstructor of Akinci et al. 2012, Algorithm 1: surface particles, the band of surface
//! vertices around them, the handler array for the gather, the scalar field on the band, and
//! the triangulation of the surface cells. A sequence that follows the fluid runs it in two
//! steps: [`sample`] up to the field on the closed band, kept for the frames beside, then
//! [`gather_along_flow`], which averages the field with theirs first.

use glam::Vec3;

use super::full_grid;
use super::prepared::{
    Prepared, Reconstruction, finish as finish_reconstruction, prepare, triangles_and_normals,
};
use crate::config::{Engine, Params};
use crate::error::Result;
use crate::field::ScalarField;
use crate::neighbours::handler_array::HandlerArray;
use crate::recon::bricks::band::Band;
use crate::recon::bricks::brick_values::BrickValues;
use crate::recon::budget::{self, PER_BRICK, PER_PARTICLE, mul};
use crate::recon::stages::band_closure::{Closed, close_band};
use crate::recon::stages::deferred_values::Deferred;
use crate::recon::stages::field_sampling::sample_field;
use crate::recon::stages::flow_mean::FlowMean;
use crate::recon::stages::lone_particles::band_half_widths;
use crate::recon::stages::side_field::SideField;
use crate::recon::stages::surface_particles::SurfaceCriteria;
use crate::recon::stages::triangulation::triangulate;
use crate::report::{FrameStats, Stage, Stages};

/// Algorithm 1; with [`Engine::FullGather`], the same gather on every vertex of the grid.
pub(crate) fn gather(
    particles: &[Vec3],
    params: &Params,
    mut stages: Stages,
) -> Result<Reconstruction> {
    let sampled = sample(particles, params, &mut stages)?;
    let Sampled {
        prepared,
        surface,
        params,
        held,
        surface_count,
        ..
    } = sampled;
    finish(
        &prepared,
        &params,
        held,
        surface_count,
        surface,
        None,
        stages,
    )
}

/// Frames t−1 and t+1 beside the frame reconstructed, for the mean along the flow.
#[derive(Clone, Copy)]
pub struct Sides<'a> {
    /// Their fields, sampled.
    pub fields: [&'a Sampled; 2],
    /// Each of frame t's particles' displacement to each; None where it has no match there.
    pub moves: [&'a [Option<Vec3>]; 2],
}

/// Frame t sampled: Algorithm 1 up to the field on the closed band, what its own surface is
/// made from ([`gather_along_flow`]) and what the frames beside it read where the fluid
/// carries their vertices ([`Sampled::side`]).
pub struct Sampled {
    prepared: Prepared,
    surface: Surface,
    /// Per brick of the band, the vertices whose values it holds (not left out), and where
    /// each word's values start.
    known: Vec<[u64; 8]>,
    word_starts: Vec<[u32; 8]>,
    /// The parameters, the full grid's support the field's.
    params: Params,
    held: u64,
    surface_count: u64,
    /// The figures so far.
    pub stats: FrameStats,
}

/// The closed band and its values, before a mean along the flow changes them.
#[derive(Clone)]
struct Surface {
    band: Band,
    values: BrickValues,
    closed: Closed,
    deferred: Deferred,
    added: usize,
    resolved: usize,
}

impl Sampled {
    /// Its field as the frames beside it read it.
    pub fn side(&self) -> SideField<'_> {
        SideField {
            band: &self.surface.band,
            values: &self.surface.values,
            known: &self.known,
            word_starts: &self.word_starts,
            handlers: self.prepared.sampling().1,
        }
    }

    /// Whether the field comes fitted to the frame, which does not hold for its neighbours.
    pub fn is_fitted(&self) -> bool {
        self.prepared.is_fitted()
    }
}

/// Algorithm 1 up to the field on the closed band; see [`Sampled`].
pub(crate) fn sample(particles: &[Vec3], params: &Params, stages: &mut Stages) -> Result<Sampled> {
    let criteria = SurfaceCriteria::of(params);
    let narrow = params.engine == Engine::NarrowBand;
    let mut prepared = prepare(particles, params, stages, narrow.then_some(&criteria))?;
    let surface = prepared.surface.take();
    let (field, samples) = prepared.sampling();
    // The full grid reaches as far as the fitted kernels do.
    let params = Params {
        support: field.support(),
        ..params.clone()
    };
    let held = prepared.heap_bytes() as u64;
    let (mut band, surface_count) = if let Some(surface) = surface {
        stages.stats.surface_particles = surface.len();
        let band = stages.run(Stage::Band, || {
            band_around(&surface, &prepared.handlers, field, &params, held)
        })?;
        (band, surface.len() as u64)
    } else {
        // The full gather has no surface particles; its estimate was checked on the grid.
        let band = stages.run(Stage::Band, || full_grid::band(particles, &params))?;
        (band, budget::surface_guess(particles.len()))
    };
    let limits = Limits::new(&params, held, surface_count);
    let planned = limits.band(band.bricks.len())?;
    if params.engine == Engine::NarrowBand {
        stages.stats.planned_bytes = planned;
    }
    let (mut values, mut deferred) = stages.run(Stage::ScalarField, || {
        Deferred::sample(&band, samples, field)
    })?;
    stages.stats.deferred_values = deferred.len();
    let closed = stages.run(Stage::Band, || {
        close_band(&mut band, &mut values, |grown, bricks| {
            limits.band(bricks)?;
            sample_field(grown, samples, field)
        })
    })?;
    let resolved = stages.run(Stage::ScalarField, || {
        deferred.resolve(&band, &mut values, &closed.tables, samples, field)
    })?;
    let known = band
        .masks
        .iter()
        .zip(deferred.masks(&band))
        .map(|(mask, left_out)| std::array::from_fn(|w| mask[w] & !left_out[w]))
        .collect();
    let word_starts = values.word_starts(&band);
    let added = closed.added;
    Ok(Sampled {
        surface: Surface {
            band,
            values,
            closed,
            deferred,
            added,
            resolved,
        },
        known,
        word_starts,
        held,
        surface_count,
        params,
        stats: stages.stats,
        prepared,
    })
}

/// Frame t's surface from its sampled field `own`; with `flow`, the field averaged along the
/// flow first with the frames beside it (`stages/flow_mean`), unless the field is fitted to
/// the frame.
pub(crate) fn gather_along_flow(
    own: &Sampled,
    flow: Option<&Sides<'_>>,
    particles: &[Vec3],
    stages: Stages,
) -> Result<Reconstruction> {
    let flow = flow
        .filter(|s| !own.is_fitted() && !s.fields.iter().any(|f| f.is_fitted()))
        .map(|s| (particles, s));
    finish(
        &own.prepared,
        &own.params,
        own.held,
        own.surface_count,
        own.surface.clone(),
        flow,
        stages,
    )
}

/// The surface from the closed band `surface` of a frame `prepared`, averaged along the flow
/// where `flow` gives frame t's particles and the sides.
fn finish(
    prepared: &Prepared,
    params: &Params,
    held: u64,
    surface_count: u64,
    surface: Surface,
    flow: Option<(&[Vec3], &Sides<'_>)>,
    mut stages: Stages,
) -> Result<Reconstruction> {
    let (field, samples) = prepared.sampling();
    let limits = Limits::new(params, held, surface_count);
    let Surface {
        mut band,
        mut values,
        mut closed,
        mut deferred,
        mut added,
        mut resolved,
    } = surface;
    let flow = flow
        .map(|(particles, sides)| {
            // Frame t's handler array with eight channels more.
            let need = held
                .saturating_add(mul(particles.len() as u64, PER_PARTICLE))
                .saturating_add(mul(particles.len() as u64, 32));
            budget::check(params, need, || {
                format!(
                    "the particles of frame t ({}) with their moves to average the field \
                     along the flow",
                    particles.len()
                )
            })?;
            stages.run(Stage::ScalarField, || {
                let lookup = prepared.handlers.cell_size();
                let fields = sides.fields.map(Sampled::side);
                FlowMean::new(particles, sides.moves, fields, params.spacing, lookup)
            })
        })
        .transpose()?;
    let held = held + flow.as_ref().map_or(0, |f| f.heap_bytes() as u64);
    if let Some(flow) = &flow {
        let mut close = |band: &mut Band, values: &mut BrickValues| {
            let closed = close_band(band, values, |grown, bricks| {
                limits.band(bricks)?;
                sample_field(grown, samples, field)
            })?;
            added += closed.added;
            Ok(closed)
        };
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
    Ok(finish_reconstruction(
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
