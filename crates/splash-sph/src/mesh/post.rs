//! Render-ready meshes (issue 25): the isosurface smoothed with Taubin's λ|μ filter, each
//! component's volume brought to that of the particles inside it (N_c·r³) by offsets along
//! the normals interleaved with smoothing, the triangles evened out by tangential relaxation,
//! and the normals recomputed. `[post]` in the configuration; `raw = true` keeps the exact
//! isosurface. Then, where asked: the mesh clipped to a box ([`clip_to_box`]), components
//! below a volume dropped ([`drop_small_components`]) and the mesh decimated ([`decimate`]).

use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::adjacency::VertexFaces;
use super::smoothing::{relax_tangentially, taubin};
use super::stars::area_weighted_normals;
use super::volume::{Components, Measures, normals_and_measures, particles_inside, restore};
use super::{TriMesh, clip_to_box, decimate, drop_small_components};
use crate::error::Result;
use crate::length::Length;

/// `[post]`: what happens to the mesh after the engine. Defaults measured on cbd-small (21
/// frames) and cbd-large frame 23 at cell r/2 (issue 25).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PostConfig {
    /// Keep the field's exact isosurface: no smoothing, no volume restoration (the meshes of
    /// splash before post-processing, byte for byte).
    pub raw: bool,
    /// λ|μ pairs of Taubin smoothing first (default 10: SSP07's bumpiness 1.99° → 1.69° on
    /// cbd-small, 2.72° → 2.35° on cbd-large f23).
    pub smoothing_iterations: u32,
    /// Taubin's shrinking factor λ (Taubin 1995: 0.33 to 0.5; default 0.5).
    pub lambda: f32,
    /// Taubin's inflating factor μ, below −λ (default −0.53: pass-band k_PB = 1/λ + 1/μ ≈ 0.11,
    /// Taubin 1995's 0.1).
    pub mu: f32,
    /// Rounds of one volume step and one λ|μ pair, so that smoothing heals what the offsets
    /// fold (default 6; 0 with `volume_steps = 0` keeps the smoothed volume).
    pub volume_rounds: u32,
    /// Largest offset of a volume step, in spacings r (default 0.25: cbd-large f23 needs 0.86 r
    /// in all; a step of 0.5 r left 1.66 % slivers, 0.25 r 1.29 % before relaxation).
    pub max_offset: f32,
    /// Tangential relaxation steps after the volume rounds (default 10: slivers on cbd-large
    /// f23 1.29 % → 0.39 %).
    pub relax_iterations: u32,
    /// Final volume steps, which bring each component within a fraction of a percent of its
    /// target (default 3).
    pub volume_steps: u32,
    /// Keep only the mesh inside this box `[min x, min y, min z, max x, max y, max z]`, the cuts
    /// capped so that it stays closed (default none). Applies with `raw` too.
    pub mesh_aabb: Option<[f32; 6]>,
    /// Drop the components enclosing less than this many particle volumes r³ (default none:
    /// keep every droplet). After the volume restoration a droplet of n particles holds n r³;
    /// with `raw` a lone particle's SSP07 sphere holds about 3.6 r³.
    pub min_component: Option<f64>,
    /// Decimate with quadric edge collapses (Garland & Heckbert 1997) keeping every vertex and
    /// every triangle's centroid within this distance of the undecimated surface, e.g. "0.1r"
    /// (default none). Applies with `raw` too.
    pub decimate: Option<Length>,
}

impl Default for PostConfig {
    fn default() -> Self {
        PostConfig {
            raw: false,
            smoothing_iterations: 10,
            lambda: 0.5,
            mu: -0.53,
            volume_rounds: 6,
            max_offset: 0.25,
            relax_iterations: 10,
            volume_steps: 3,
            mesh_aabb: None,
            min_component: None,
            decimate: None,
        }
    }
}

impl PostConfig {
    /// Whether [`postprocess`] would change a mesh: false only for `raw` without a box, a
    /// smallest component or a decimation.
    pub fn changes_mesh(&self) -> bool {
        !self.raw
            || self.mesh_aabb.is_some()
            || self.min_component.is_some()
            || self.decimate.is_some()
    }

    /// Checks the ranges the TOML types cannot express, naming the key.
    pub fn validate(&self) -> Result<()> {
        if !(self.lambda > 0.0 && self.lambda < 1.0) {
            bail_config!("post.lambda ({}) must lie in (0, 1)", self.lambda);
        }
        if !(self.mu < -self.lambda && self.mu > -1.0) {
            bail_config!(
                "post.mu ({}) must lie in (-1, -lambda) (lambda = {})",
                self.mu,
                self.lambda
            );
        }
        if let Some(b) = &self.mesh_aabb
            && !(0..3).all(|i| b[i].is_finite() && b[i + 3].is_finite() && b[i] < b[i + 3])
        {
            bail_config!(
                "post.mesh_aabb must be six finite numbers MINX, MINY, MINZ, MAXX, MAXY, MAXZ \
                 with each minimum below its maximum"
            );
        }
        if let Some(v) = self.min_component
            && !(v.is_finite() && v >= 0.0)
        {
            bail_config!("post.min_component ({v}) must be a volume of at least 0 r³");
        }
        if let Some(d) = self.decimate {
            d.check_positive("post.decimate")?;
        }
        if !(self.max_offset > 0.0 && self.max_offset <= 1.0) {
            bail_config!(
                "post.max_offset ({}) must lie in (0, 1] spacings",
                self.max_offset
            );
        }
        Ok(())
    }
}

/// Post-processes `mesh`, the surface of `particles` at spacing `spacing` reconstructed with
/// cells of `cell`, in the current rayon pool: smoothing and volume restoration (unless
/// `raw`), then the box, the small components and the decimation where `config` asks for
/// them. `normals`: whether the smoothed mesh gets (area-weighted) vertex normals; the engine's
/// would no longer fit the moved vertices. The same mesh gives the same bytes on any number of
/// threads.
pub fn postprocess(
    mesh: &mut TriMesh,
    particles: &[Vec3],
    spacing: f32,
    cell: f32,
    config: &PostConfig,
    normals: bool,
) -> Result<()> {
    if !config.raw {
        smooth_and_restore(mesh, particles, spacing, cell, config, normals);
    }
    // Clipped after smoothing, so that the caps stay flat; components dropped after clipping,
    // which can leave small pieces; decimated last, against the mesh that would be written.
    if let Some(aabb) = config.mesh_aabb {
        *mesh = clip_to_box(mesh, aabb)?;
    }
    if let Some(v) = config.min_component {
        *mesh = drop_small_components(mesh, v * f64::from(spacing).powi(3))?.0;
    }
    if let Some(d) = config.decimate {
        // The decimation gives the new faces area-weighted normals: made here after it, the
        // old ones freed before it instead of held beside its working arrays.
        let normals = !std::mem::take(&mut mesh.normals).is_empty();
        *mesh = decimate(mesh, d.resolve(spacing))?;
        if normals {
            mesh.normals = area_weighted_normals(&mesh.vertices, &mesh.triangles);
        }
    }
    Ok(())
}

/// Smooths `mesh` and restores each component's volume (see the module's header). Keeps the
/// triangles (and so the topology); moves the vertices and recomputes the normals (when the
/// mesh has normals).
fn smooth_and_restore(
    mesh: &mut TriMesh,
    particles: &[Vec3],
    spacing: f32,
    cell: f32,
    config: &PostConfig,
    wants_normals: bool,
) {
    if mesh.triangles.is_empty() {
        return;
    }
    let rings = VertexFaces::new(mesh.vertices.len(), &mesh.triangles);
    let components = Components::new(&rings);
    let raw_volumes = components.volumes_and_areas(&mesh.vertices, &mesh.triangles);
    let (lambda, mu) = (config.lambda, config.mu);
    let mut scratch = vec![Vec3::ZERO; mesh.vertices.len()];
    let triangles = &mesh.triangles;
    let vertices = &mut mesh.vertices;
    taubin(
        vertices,
        &mut scratch,
        &rings,
        config.smoothing_iterations,
        lambda,
        mu,
    );
    let normals = &mut mesh.normals;
    normals.resize(vertices.len(), Vec3::ZERO);
    let mut measures = Measures::default();
    normals_and_measures(vertices, triangles, &rings, normals, &mut measures);

    let targets: Vec<f64> = if config.volume_rounds + config.volume_steps > 0 {
        let inside = particles_inside(
            &components,
            &raw_volumes,
            vertices,
            triangles,
            particles,
            cell,
        );
        let r3 = f64::from(spacing).powi(3);
        // Bubbles (negative volume) and blobs without a particle keep their raw volume.
        raw_volumes
            .iter()
            .zip(&inside)
            .map(|(&(v, _), &n)| if v > 0.0 && n > 0 { n as f64 * r3 } else { v })
            .collect()
    } else {
        Vec::new()
    };
    let max_step = config.max_offset * spacing;
    let volume_steps =
        |vertices: &mut [Vec3], normals: &mut [Vec3], measures: &mut Measures, steps: u32| {
            if !targets.is_empty() {
                restore(
                    vertices,
                    normals,
                    measures,
                    triangles,
                    &rings,
                    &components,
                    &targets,
                    steps,
                    max_step,
                );
            }
        };
    for _ in 0..config.volume_rounds {
        taubin(vertices, &mut scratch, &rings, 1, lambda, mu);
        normals_and_measures(vertices, triangles, &rings, normals, &mut measures);
        volume_steps(vertices, normals, &mut measures, 1);
    }
    relax_tangentially(
        vertices,
        &mut scratch,
        normals,
        &rings,
        config.relax_iterations,
        0.5,
    );
    normals_and_measures(vertices, triangles, &rings, normals, &mut measures);
    volume_steps(vertices, normals, &mut measures, config.volume_steps);
    if !wants_normals {
        *normals = Vec::new();
    }
}
