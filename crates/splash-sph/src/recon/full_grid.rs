//! The full grid of the engines without a narrow band (`full-gather`, `scatter`): its extent,
//! the memory those engines need for it, and the `--max-memory` check made before allocating.
//! The narrow-band engine reports the same grid (Table 1's "grid res." and total vertices)
//! without ever allocating it.

use crate::config::{Engine, Params};
use crate::error::Result;
use glam::{IVec3, Vec3};

use super::band::{BRICK_VERTICES, Band, brick_of};
use crate::bytes::human;

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
        (self.hi - self.lo + 1).to_array().map(|n| n.max(0) as u64)
    }

    pub fn vertices(&self) -> u64 {
        self.resolution().iter().product()
    }

    /// Bricks of 8³ vertices covering the grid, as [`Band::full`] allocates them.
    pub fn bricks(&self) -> u64 {
        let n = brick_of(self.hi) - brick_of(self.lo) + 1;
        n.to_array().iter().map(|&k| k.max(0) as u64).product()
    }
}

/// Heap bytes per brick of a full band, besides its values: mask, coordinates, index entry
/// and the triangulation's per-brick edge table (measured, rounded up).
const BRICK_OVERHEAD: u64 = 64 + 12 + 40 + 480;
/// Heap bytes per particle: the handler array (sort pairs, positions, cell starts).
const PER_PARTICLE: u64 = 48;

/// Peak heap an engine needs on `grid`, in bytes, without the mesh (which follows the surface
/// and is not known beforehand: on fixtures/frame_0040 at r/2 the full gather's measured peak
/// is 1.45× this figure, the scatter's 0.98×, its sums dominating); None for the narrow band
/// and the slices engine, whose memory follows the surface.
pub fn needed_bytes(params: &Params, grid: &Grid, particles: usize) -> Result<Option<u64>> {
    let band = grid.bricks() * (BRICK_VERTICES as u64 * 4 + BRICK_OVERHEAD);
    Ok(match params.engine {
        Engine::NarrowBand | Engine::Slices => None,
        Engine::FullGather => Some(band + particles as u64 * PER_PARTICLE),
        // One set of the field's sums per vertex, then the values per brick.
        Engine::Scatter => {
            let sums = params.scattering()?.sums_per_vertex() * size_of::<f32>();
            Some(band + grid.vertices() * sums as u64)
        }
    })
}

/// Refuses a full-grid engine whose grid needs more than the memory limit.
pub fn check(params: &Params, grid: &Grid, particles: usize) -> Result<()> {
    let (engine, limit) = (params.engine, params.max_memory);
    let Some(need) = needed_bytes(params, grid, particles)? else {
        return Ok(());
    };
    if need > limit {
        let [x, y, z] = grid.resolution();
        bail_limit!(
            "the {} engine would need about {} for its full grid of {x} × {y} × {z} = {} vertices, \
             above the limit of {} (--max-memory); use the narrow-band engine, a larger cell, or \
             raise --max-memory",
            engine.name(),
            human(need),
            grid.vertices(),
            human(limit)
        );
    }
    Ok(())
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
