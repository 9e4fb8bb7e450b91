//! The library's front door: a validated configuration, its thread pool, and the
//! reconstruction of one frame after another with it.

use std::sync::Arc;

use glam::Vec3;

use crate::attributes;
use crate::config::{Config, Params};
use crate::error::{Error, Result};
use crate::io::Attribute;
use crate::mesh::TriMesh;
use crate::recon::full_grid::{self, Grid};
use crate::recon::{self, Reconstruction};
use crate::report::Observer;

/// Reconstructs frames with one configuration: `Reconstructor::new(config)?.reconstruct(&positions)?`.
///
/// Cheap to clone (the thread pool is shared). With `config.threads` set it owns a pool of
/// that many workers; without, it runs in the caller's rayon pool (all cores by default).
#[derive(Debug, Clone)]
pub struct Reconstructor {
    config: Config,
    params: Params,
    pool: Option<Arc<rayon::ThreadPool>>,
}

impl Reconstructor {
    /// Validates `config`, which must give the particle spacing (see
    /// [`estimate_spacing`](crate::estimate_spacing) when it is not known).
    pub fn new(config: Config) -> Result<Reconstructor> {
        config.validate()?;
        let Some(r) = config.spacing else {
            return Err(Error::config(
                "the particle spacing is not set: give it in the configuration (spacing = r), \
                 or estimate it once per sequence with estimate_spacing",
            ));
        };
        let pool = match config.threads {
            Some(n) => Some(Arc::new(
                rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .build()
                    .map_err(|e| Error::config(format!("cannot start {n} worker threads: {e}")))?,
            )),
            None => None,
        };
        Ok(Reconstructor {
            params: Params::resolve(&config, r),
            config,
            pool,
        })
    }

    /// The configuration, as validated.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// The field's support radius in world units: particles farther than this from a point do
    /// not change the field there (and do not reach [`interpolate`](Self::interpolate)d values).
    pub fn support(&self) -> f32 {
        self.params.support
    }

    /// The closed, outward-oriented surface mesh of `positions`, with its report (counts and
    /// array bytes; no times: see [`reconstruct_observed`](Self::reconstruct_observed)).
    /// Coordinates must be finite.
    pub fn reconstruct(&self, positions: &[Vec3]) -> Result<Reconstruction> {
        self.run(positions, None)
    }

    /// [`reconstruct`](Self::reconstruct), with `observer` measuring each stage for the report.
    pub fn reconstruct_observed(
        &self,
        positions: &[Vec3],
        observer: &mut dyn Observer,
    ) -> Result<Reconstruction> {
        self.run(positions, Some(observer))
    }

    fn run(
        &self,
        positions: &[Vec3],
        observer: Option<&mut dyn Observer>,
    ) -> Result<Reconstruction> {
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            let p = positions[i];
            return Err(Error::input(format!(
                "particle {i} has a non-finite coordinate: ({}, {}, {})",
                p.x, p.y, p.z
            )));
        }
        self.install(|| recon::reconstruct(positions, &self.params, observer))
    }

    /// A per-particle attribute (velocities, densities, …) interpolated onto the vertices of
    /// `mesh`: the kernel-weighted mean of the particles within the field's support, with the
    /// weights k(s) = max(0, (1 − s²)³) of SSP07, normalised by their sum (Shepard), so that a
    /// constant attribute stays that constant. `values` has one entry per position; the result
    /// one per vertex, of the same kind.
    pub fn interpolate(
        &self,
        mesh: &TriMesh,
        positions: &[Vec3],
        values: &Attribute,
    ) -> Result<Attribute> {
        let mut all = self.interpolate_all(mesh, positions, &[values])?;
        Ok(all.pop().expect("one attribute in, one out"))
    }

    /// [`interpolate`](Self::interpolate) for several attributes at once, through one
    /// neighbour search.
    pub fn interpolate_all(
        &self,
        mesh: &TriMesh,
        positions: &[Vec3],
        values: &[&Attribute],
    ) -> Result<Vec<Attribute>> {
        self.install(|| {
            attributes::interpolate(&mesh.vertices, positions, values, self.params.support)
        })
    }

    /// The heap, in bytes, that a full-grid engine plans for `positions` before it allocates
    /// (the memory limit is checked against it; the mesh comes on top); None for the engines
    /// whose memory follows the surface.
    pub fn planned_memory(&self, positions: &[Vec3]) -> Result<Option<u64>> {
        let p = &self.params;
        let grid = Grid::around(positions, p.cell, p.support)?;
        full_grid::needed_bytes(p, &grid, positions.len())
    }

    fn install<T: Send>(&self, f: impl FnOnce() -> T + Send) -> T {
        match &self.pool {
            Some(pool) => pool.install(f),
            None => f(),
        }
    }
}
