//! The library's front door: a validated configuration, its thread pool, and the
//! reconstruction of one frame after another with it.

use std::sync::Arc;

use glam::Vec3;

use crate::attributes;
use crate::config::Baseline;
use crate::config::{Config, Normals, Params};
use crate::error::{Error, Result, figure};
use crate::io::Attribute;
use crate::mesh::TriMesh;
use crate::mesh::post::{Volumes, stages as post_stages};
use crate::recon::engines::full_grid::{self, Grid};
use crate::recon::{self, Reconstruction, Sampled, Sides};
use crate::report::{Observer, Stage, Stages};
use crate::worker_pool::worker_pool;

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
        let pool = worker_pool(config.threads)?;
        let mut params = Params::resolve(&config, r);
        if !config.post.raw {
            // Smoothing moves the vertices: the post-processing gives the normals, so the
            // engine's (the field's gradient, 7 % of a 1-thread SSP07 run) are not computed.
            params.normals = Normals::None;
        }
        Ok(Reconstructor {
            params,
            config,
            pool,
        })
    }

    /// This reconstructor, running `baseline` instead of its engine: the surface-following
    /// Marching Cubes that Rosenberg & Birdwell 2008 compare Marching Slices with (Fig. 7),
    /// which give the slices engine's mesh with other data structures (`splash bench slices`).
    // Hidden: only `splash bench slices` runs the baselines, whose engines stay inside the
    // library (they share its field sampling); no part of the documented API.
    #[doc(hidden)]
    pub fn with_baseline(mut self, baseline: Baseline) -> Reconstructor {
        self.params.baseline = Some(baseline);
        self
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
        self.reconstruct_along_flow(positions, None, None, None)
    }

    /// [`reconstruct`](Self::reconstruct), with `observer` measuring each stage for the report.
    pub fn reconstruct_observed(
        &self,
        positions: &[Vec3],
        observer: &mut dyn Observer,
    ) -> Result<Reconstruction> {
        self.reconstruct_along_flow(positions, None, None, Some(observer))
    }

    /// Frame `positions`' field sampled on its closed band, for
    /// [`reconstruct_along_flow`](Self::reconstruct_along_flow) to make its surface from and
    /// the frames beside it to average their fields with (None where the engine does not
    /// sample so, or there are no particles); `observer` measures its stages.
    pub(crate) fn sample(
        &self,
        positions: &[Vec3],
        observer: Option<&mut dyn Observer>,
    ) -> Result<Option<Sampled>> {
        self.check_positions(positions)?;
        self.install(|| recon::sample(positions, &self.params, observer))
    }

    /// Non-finite coordinates, and grids too fine for the frame, as errors.
    fn check_positions(&self, positions: &[Vec3]) -> Result<()> {
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            let p = positions[i];
            return Err(Error::input(format!(
                "particle {i} has a non-finite coordinate: ({}, {}, {})",
                p.x, p.y, p.z
            )));
        }
        self.check_resolution(positions)
    }

    /// [`reconstruct`](Self::reconstruct) with the field averaged along the flow with the
    /// frames beside (`sides`: their sampled fields, and the moves of `positions` to them),
    /// where the engine and field allow it, made from `own` ([`sample`](Self::sample) of
    /// `positions`) where given; `observer` as in
    /// [`reconstruct_observed`](Self::reconstruct_observed).
    pub(crate) fn reconstruct_along_flow(
        &self,
        positions: &[Vec3],
        own: Option<&Sampled>,
        sides: Option<&Sides<'_>>,
        mut observer: Option<&mut dyn Observer>,
    ) -> Result<Reconstruction> {
        if own.is_none() {
            self.check_positions(positions)?;
        }
        self.install(|| {
            let reborrowed: Option<&mut dyn Observer> = match &mut observer {
                Some(o) => Some(&mut **o),
                None => None,
            };
            let mut out =
                recon::reconstruct_along_flow(positions, own, sides, &self.params, reborrowed)?;
            let post = &self.config.post;
            if post.changes_mesh() && !out.mesh.is_empty() {
                let (r, cell) = (self.params.spacing, self.params.cell);
                let normals = self.config.normals != Normals::None;
                let mut stages = Stages::start(out.stats, observer);
                out.close = stages
                    .run(Stage::Post, || {
                        let volumes = Volumes::Particles {
                            particles: positions,
                            cell,
                        };
                        post_stages(&mut out.mesh, r, &volumes, post, normals)
                    })?
                    .unwrap_or_default();
                out.stats = stages.stats;
                out.stats.heap_peak = out.stats.stage_heap.max();
                out.stats.triangles = out.mesh.triangles.len();
                out.stats.vertices = out.mesh.vertices.len();
            }
            Ok(out)
        })
    }

    /// Refuses coordinates so large that f32's steps there are a sizeable part of a cell: the
    /// particles would sit on a coarse lattice of their own, and the mesh would be wrong
    /// without a sign of it (a ball 10⁵ units from the origin at r = 0.014).
    fn check_resolution(&self, positions: &[Vec3]) -> Result<()> {
        let largest = positions
            .iter()
            .map(|p| p.abs().max_element())
            .fold(0.0f32, f32::max);
        // The distance between neighbouring f32 values near `largest`.
        let step = largest * f32::EPSILON;
        let cell = self.params.cell;
        if step > cell / 4.0 {
            return Err(Error::input(format!(
                "coordinates up to {} are beyond f32's resolution for cell {}: f32 values \
                 there are {} apart, more than a quarter of a cell; move the \
                 origin into the fluid (subtract its centre from the coordinates) or use a larger \
                 cell",
                figure(largest),
                figure(cell),
                figure(step)
            )));
        }
        Ok(())
    }

    /// Signs that the configuration does not fit `positions`, in words, for the caller to
    /// show (the reconstruction goes ahead regardless): the frame is smaller than one cell, or
    /// the spacing is 2× or more off what [`estimate_spacing`](crate::estimate_spacing) finds
    /// in it. The estimate reads the whole frame, so callers check the first frame of a
    /// sequence rather than every one.
    pub fn warnings(&self, positions: &[Vec3]) -> Vec<String> {
        let mut warnings = Vec::new();
        let finite = positions.iter().filter(|p| p.is_finite());
        let (lo, hi) = finite.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        });
        let (r, cell) = (self.params.spacing, self.params.cell);
        let extent = (hi - lo).max_element();
        if positions.len() > 1 && extent > 0.0 && extent < cell {
            warnings.push(format!(
                "the particles span {}, less than one cell ({}, at spacing r = {}): the mesh \
                 can only be a blob; is the spacing right?",
                figure(extent),
                figure(cell),
                figure(r)
            ));
        }
        if let Some(estimate) = crate::spacing::rough_spacing(positions) {
            let ratio = r / estimate;
            if !(0.5..=2.0).contains(&ratio) {
                warnings.push(format!(
                    "the spacing r = {} is {ratio:.3}× the {} that the particles' \
                     density suggests: the mesh will be {}; check --spacing (--particle-radius is \
                     half the spacing)",
                    figure(r),
                    figure(estimate),
                    if ratio > 1.0 {
                        "a blob that fills the gaps between separate parts"
                    } else {
                        "broken into droplets around single particles"
                    },
                ));
            }
        }
        warnings
    }

    /// A per-particle attribute (velocities, densities, …) interpolated onto the vertices of
    /// `mesh`: the mean of the particles within the field's support weighted by the field's
    /// own kernel (SSP07's and ZB05's (1 − s²)³, the density field's cubic spline, the blobbies'
    /// Gaussian, the metaballs' polynomial; for the anisotropic field the cubic spline of its
    /// neighbourhood radius h, an interior particle's kernel), normalised by the weights' sum
    /// (Shepard), so that a constant attribute stays that constant. `values` has one entry per position; the result
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
        self.interpolate_at(&mesh.vertices, positions, values)
    }

    /// [`interpolate_all`](Self::interpolate_all) at any `points` (a level set's voxels).
    pub fn interpolate_at(
        &self,
        points: &[Vec3],
        positions: &[Vec3],
        values: &[&Attribute],
    ) -> Result<Vec<Attribute>> {
        self.install(|| {
            let kernel = self.params.field.radial_kernel();
            attributes::interpolate(points, positions, values, &kernel, self.params.cell)
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

    /// Runs `f` in this reconstructor's thread pool (the caller's when `threads` is unset).
    pub(crate) fn install<T: Send>(&self, f: impl FnOnce() -> T + Send) -> T {
        match &self.pool {
            Some(pool) => pool.install(f),
            None => f(),
        }
    }
}
