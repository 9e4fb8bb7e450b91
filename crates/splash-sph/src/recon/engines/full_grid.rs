//! The full grid of the engines without a narrow band (`full-gather`, `scatter`): its extent,
//! the memory those engines need for it, and the `--max-memory` check made before allocating.
//! The narrow-band engine reports the same grid (Table 1's "grid res." and total vertices)
//! without ever allocating it.

use crate::config::{Engine, Params};
use crate::error::Result;
use glam::{IVec3, Vec3};

use crate::recon::bricks::band::{Band, brick_of};
use crate::recon::budget::{self, PER_BRICK, PER_PARTICLE, mul};

/// The vertices of the particles' bounding box widened by the field's support.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Grid {
    pub lo: IVec3,
    pub hi: IVec3,
}

impl Grid {
    pub fn around(particles: &[Vec3], cell: f32, support: f32) -> Result<Grid> {
        let (lo, hi) = bounds(particles);
        let (lo, hi) = Band::full_extent(lo, hi, cell, support)?;
        Ok(Grid { lo, hi })
    }

    /// Vertices per axis (the paper's "grid res.": 243 × 204 × 243 at r becomes
    /// 485 × 409 × 486 at r/2, i.e. n → 2n − 1).
    pub fn resolution(&self) -> [u64; 3] {
        (self.hi.as_i64vec3() - self.lo.as_i64vec3() + 1)
            .to_array()
            .map(|n| n.max(0) as u64)
    }

    /// Vertices of the grid, saturating at u64::MAX.
    pub fn vertices(&self) -> u64 {
        self.resolution()
            .iter()
            .fold(1, |a, &n| a.saturating_mul(n))
    }

    /// Bricks of 8³ vertices covering the grid, as [`Band::full`] allocates them (saturating).
    pub fn bricks(&self) -> u64 {
        let n = brick_of(self.hi).as_i64vec3() - brick_of(self.lo).as_i64vec3() + 1;
        n.to_array()
            .iter()
            .fold(1u64, |a, &k| a.saturating_mul(k.max(0) as u64))
    }
}

/// Peak heap an engine needs on `grid`, in bytes, with the mesh estimated from the particle
/// count (see [`budget`]); None for the narrow band and the slices engine, whose memory
/// follows the surface and is estimated as they find it. The full gather holds the handler
/// array, the values of every brick and the mesh; the scatter its per-vertex sums with the
/// values, then the values with the mesh and the normals' handler array.
pub fn needed_bytes(params: &Params, grid: &Grid, particles: usize) -> Result<Option<u64>> {
    let band = mul(grid.bricks(), PER_BRICK);
    let handlers = mul(particles as u64, PER_PARTICLE);
    let mesh = budget::mesh_bytes(budget::mesh_vertices(
        params,
        budget::surface_guess(particles),
    ));
    Ok(match params.engine {
        Engine::NarrowBand | Engine::Slices => None,
        Engine::FullGather => Some(band.saturating_add(handlers).saturating_add(mesh)),
        Engine::Scatter => {
            let sums = params.scattering()?.sums_per_vertex() * size_of::<f32>();
            let scatter = mul(grid.vertices(), sums as u64);
            let triangulation = handlers.saturating_add(mesh);
            Some(band.saturating_add(scatter.max(triangulation)))
        }
    })
}

/// Refuses a full-grid engine whose grid needs more than the memory limit; returns the
/// estimate (None for the other engines).
pub fn check(params: &Params, grid: &Grid, particles: usize) -> Result<Option<u64>> {
    let Some(need) = needed_bytes(params, grid, particles)? else {
        return Ok(None);
    };
    let [x, y, z] = grid.resolution();
    budget::check(params, need, || {
        format!(
            "its full grid of {x} × {y} × {z} = {} vertices (the narrow-band engine needs only \
             the surface's)",
            grid.vertices()
        )
    })
    .map(Some)
}

/// Every vertex of the particles' bounding box widened by the field's support.
pub fn band(particles: &[Vec3], params: &Params) -> Result<Band> {
    let (lo, hi) = bounds(particles);
    Band::full(lo, hi, params.cell, params.support)
}

pub fn bounds(particles: &[Vec3]) -> (Vec3, Vec3) {
    particles
        .iter()
        .fold((Vec3::MAX, Vec3::MIN), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        })
}
