//! Marching Correctors (Schindler et al. 2012): isosurfaces of any SPH quantity, exact with
//! respect to the SPH interpolant. A virtual grid whose cells are materialised only as seeds or
//! when the surface crosses them, seeds from particle pairs, surface following with a slice
//! cache, Newton correction of every vertex along its edge, trimming at free boundaries by the
//! sum of weights, and normals from the SPH gradient. The quantity may be derived from a
//! velocity: its magnitude, vorticity or λ2 (the paper's Fig. 7).

mod assembly;
pub(crate) mod lambda2;
pub(crate) mod quantity;
pub(crate) mod seed_cells;
mod slice_cache;
pub(crate) mod sph_interpolant;
pub(crate) mod stats;
pub(crate) mod surface_following;
mod trimming;
pub(crate) mod virtual_grid;

use std::collections::BTreeMap;
use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;

use crate::config::Config;
use crate::error::{Error, Result};
use crate::io::Attribute;
use crate::mesh::TriMesh;

pub use crate::config::iso::IsoConfig;
pub use quantity::{Derived, IsoRequest};
pub use stats::{CORRECTION_BINS, CorrectionStats, IsoStats, IsoTimings};

/// Particles whose neighbours are counted for [`IsoStats::support_neighbours`]: a few
/// milliseconds, and the mean within a few percent of all particles'.
const NEIGHBOUR_SAMPLES: usize = 4096;

/// Fewest particles, on average, in a kernel's support before [`Isosurface::warnings`] says the
/// kernel scale is too small. A lattice of spacing r holds 4/3 π (s/r)³ − 1 others within s:
/// 33 at the usual support 2r, 13 at scale 0.75, 3 at 0.5. On cbd-small frame 40 (|v| = 1.5)
/// the mean falls 27.4 → 11.7 → 9.5 → 5.7 → 2.2 at scales 1, 0.75, 0.7, 0.6, 0.5 while the
/// triangles go 87 310 → 91 218 → 78 250 → 26 423 → 212: below 10 the sums of weights between
/// particles fall under the node threshold, cells are discarded and the surface breaks up.
pub(crate) const FEW_NEIGHBOURS: f64 = 10.0;

/// An isosurface: its mesh (normals from ∇A, pointing to larger A), the extra attributes
/// interpolated onto its vertices (named as `config.output.attributes`), and its figures.
#[derive(Debug, Clone)]
pub struct Isosurface {
    /// The triangles, wound counter-clockwise seen from the side where A is above the level.
    pub mesh: TriMesh,
    /// `config.output.attributes`, one value per vertex each.
    pub attributes: Vec<(String, Attribute)>,
    /// Counts and times.
    pub stats: IsoStats,
    /// Signs that the settings do not fit the particles, in words, for the caller to show:
    /// a kernel scale that leaves fewer than 10 particles in a support.
    pub warnings: Vec<String>,
}

/// The isosurface `request` of the particles at `positions` with per-particle `attributes`
/// (every column of the frame, by name), as `config` says: the spacing (required), the virtual
/// cell `cell`, `[iso]`, `threads` and the extra attributes of `output.attributes`.
pub fn extract(
    positions: &[Vec3],
    attributes: BTreeMap<String, Attribute>,
    request: &IsoRequest,
    config: &Config,
) -> Result<Isosurface> {
    extract_then(
        positions,
        attributes,
        request,
        config,
        |mut surface, extras| {
            extras.onto_vertices(&mut surface);
            Ok(surface)
        },
    )
}

/// The extra attributes of an isosurface's particles (`config.output.attributes`), to sample
/// at other points than its vertices: a level set's voxels.
pub(crate) struct Extras<'a> {
    it: &'a sph_interpolant::Interpolant,
    names: &'a [String],
}

impl Extras<'_> {
    /// The extra attributes at `points`, one value per point each, interpolated as at the
    /// isosurface's vertices.
    pub(crate) fn at(&self, points: &[Vec3]) -> Vec<(String, Attribute)> {
        let width: usize = self.it.channels.extras.iter().map(|e| e.1).sum();
        let mut rows = vec![0.0f32; points.len() * width];
        if width > 0 {
            rows.par_chunks_mut(width)
                .zip(points.par_iter())
                .for_each(|(out, &x)| self.it.extras_at(x, out));
        }
        split_extras(self.names, &self.it.channels.extras, &rows)
    }

    /// Samples the extra attributes at `surface`'s vertices, the time counted into its
    /// finishing; without particles, each is an empty column.
    pub(crate) fn onto_vertices(&self, surface: &mut Isosurface) {
        if self.it.handlers.positions.is_empty() {
            surface.attributes = self
                .names
                .iter()
                .map(|n| (n.clone(), Attribute::Scalar(Vec::new())))
                .collect();
            return;
        }
        let start = Instant::now();
        surface.attributes = self.at(&surface.mesh.vertices);
        surface.stats.timings.finishing += start.elapsed();
    }
}

/// [`extract`] without the vertex attributes, then `then` with the isosurface and its
/// particles' [`Extras`] (to sample them at its vertices, [`Extras::onto_vertices`], or
/// elsewhere), in the same worker pool.
pub(crate) fn extract_then<T: Send>(
    positions: &[Vec3],
    mut attributes: BTreeMap<String, Attribute>,
    request: &IsoRequest,
    config: &Config,
    then: impl FnOnce(Isosurface, &Extras<'_>) -> Result<T> + Send,
) -> Result<T> {
    config.validate()?;
    let Some(r) = config.spacing else {
        return Err(Error::config("the isosurface needs the particle spacing"));
    };
    if !request.level.is_finite() {
        bail_config!("the level must be a finite number, got {}", request.level);
    }
    let iso = &config.iso;
    let pool = crate::worker_pool::worker_pool(config.threads)?;
    let run = move || -> Result<T> {
        let level = f64::from(request.level);
        let start = Instant::now();
        let mut timings = IsoTimings::default();
        let it = quantity::interpolant(
            positions,
            &mut attributes,
            request,
            &config.output.attributes,
            iso.support.resolve(r),
            iso.kernel_scale,
            iso.shepard,
        )?;
        let cell = config.cell.resolve(r);
        let mut stats = IsoStats {
            level,
            cell,
            support_neighbours: it.mean_neighbours(NEIGHBOUR_SAMPLES),
            ..IsoStats::default()
        };
        let mut mesh = TriMesh::default();
        let names = config.output.attributes.clone();
        let extras = Extras {
            it: &it,
            names: &names,
        };
        if positions.is_empty() {
            let empty = Isosurface {
                mesh: TriMesh::default(),
                attributes: Vec::new(),
                stats,
                warnings: Vec::new(),
            };
            return then(empty, &extras);
        }
        let (lo, hi) = positions
            .iter()
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        let reach = it.handlers.cell_size();
        let grid = virtual_grid::VirtualGrid::new(cell, lo, hi, reach)?;
        let extent = ((hi - lo + 2.0 * reach) / cell).ceil().as_dvec3();
        stats.virtual_cells = (extent.x * extent.y * extent.z).min(u64::MAX as f64) as u64;
        timings.grid_construction = start.elapsed();

        let start = Instant::now();
        let seeds = seed_cells::seed_cells(&it, &grid, level, iso.seed_reach);
        stats.seed_cells = seeds.len();
        timings.seed_cells = start.elapsed();

        let start = Instant::now();
        let followed = surface_following::follow(
            &it,
            &grid,
            &seeds,
            &surface_following::Following {
                level,
                node_threshold: f64::from(iso.node_threshold),
                cache_slices: iso.cache_slices,
                max_cells: iso.max_cells,
            },
        )?;
        drop(seeds);
        stats.visited_cells = followed.visited;
        stats.crossed_cells = followed.cells.len();
        stats.discarded_cells = followed.discarded;
        stats.node_lookups = followed.cache.lookups;
        stats.node_evaluations = followed.cache.evaluations;
        stats.cache_hit_ratio = followed.cache.hit_ratio();
        stats.cache_peak_nodes = followed.cache.peak_nodes;
        let tri = assembly::triangulate(&followed.cells, &grid);
        drop(followed);
        stats.untrimmed_triangles = tri.triangles.len();
        timings.surface_extraction = start.elapsed();

        let start = Instant::now();
        let (vertices, correction) = assembly::place(&it, &tri.edges, level, iso.correct);
        stats.correction = correction;
        timings.correction = start.elapsed();

        let start = Instant::now();
        let done = assembly::finish(
            &it,
            vertices,
            &tri.triangles,
            level,
            iso.correct,
            f64::from(iso.vertex_threshold),
        );
        stats.trim_cases = done.trim_cases;
        mesh.vertices = done.vertices;
        mesh.normals = done.normals;
        mesh.triangles = done.triangles;
        stats.vertices = mesh.vertices.len();
        stats.triangles = mesh.triangles.len();
        timings.finishing = start.elapsed();
        stats.timings = timings;
        let warnings = kernel_warnings(&stats, iso.kernel_scale);
        let surface = Isosurface {
            mesh,
            attributes: Vec::new(),
            stats,
            warnings,
        };
        then(surface, &extras)
    };
    match pool {
        Some(pool) => pool.install(run),
        None => run(),
    }
}

/// The warning for a kernel scale that leaves too few particles in a support, if it does.
fn kernel_warnings(stats: &IsoStats, kernel_scale: f32) -> Vec<String> {
    if stats.support_neighbours >= FEW_NEIGHBOURS {
        return Vec::new();
    }
    vec![format!(
        "a particle's kernel reaches {:.1} others on average (kernel scale {kernel_scale}), fewer \
         than {FEW_NEIGHBOURS}: the SPH sums between particles fall below the thresholds and the \
         isosurface breaks up into fragments or vanishes; use a larger --kernel-scale (1 is the \
         simulation's support)",
        stats.support_neighbours
    )]
}

/// The per-vertex rows of interpolated extras split into one attribute per name.
fn split_extras(
    names: &[String],
    widths: &[(usize, usize)],
    rows: &[f32],
) -> Vec<(String, Attribute)> {
    let total: usize = widths.iter().map(|w| w.1).sum();
    let mut offset = 0;
    names
        .iter()
        .zip(widths)
        .map(|(name, &(_, w))| {
            let column = |c: usize| rows.iter().skip(offset + c).step_by(total.max(1)).copied();
            let a = if w == 1 {
                Attribute::Scalar(column(0).collect())
            } else {
                Attribute::Vector(
                    column(0)
                        .zip(column(1))
                        .zip(column(2))
                        .map(|((x, y), z)| Vec3::new(x, y, z))
                        .collect(),
                )
            };
            offset += w;
            (name.clone(), a)
        })
        .collect()
}
