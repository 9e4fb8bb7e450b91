//! Render-ready meshes (issue 25): the isosurface's triangles evened out by tangential
//! relaxation, then smoothed with Taubin's λ|μ filter, its volume brought to that of the
//! particles inside it (N·r³; each component's to N_c·r³ with
//! `volume_scope = "component"`) by offsets along the normals interleaved with smoothing,
//! where asked the edges bisected where the surface bends (`refine_angle`), the triangles
//! evened out by tangential relaxation, and the normals recomputed. `[post]` in the
//! configuration; `raw = true` keeps the exact isosurface. Then, where asked: the mesh clipped
//! to a box ([`clip_to_box`]), components below a volume dropped ([`drop_small_components`])
//! and the mesh decimated ([`decimate`]).
//! [`postprocess_mesh`] runs the same on any closed mesh, checked first, with each component
//! keeping its own volume when there are no particles.

mod clearance;
mod clipping;
mod crossings;
mod decimation;
pub(crate) mod refinement;
pub(crate) mod smoothing;
pub(crate) mod volume;

pub use clipping::clip_to_box;
pub(crate) use crossings::put_back_near;
use crossings::uncross;
pub use decimation::decimate;
pub use volume::VolumeScope;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::length::Length;
use crate::mesh::adjacency::{Neighbours, VertexFaces};
use crate::mesh::stars::{area_weighted_normals, validate};
use crate::mesh::topology::topology;
use crate::mesh::{TriMesh, drop_small_components};
use clearance::Clearance;
use refinement::refine_bends;
use smoothing::{relax_tangentially, taubin, vertex_normals};
use volume::{
    Components, Measures, first_order_offsets, normals_and_measures, particles_inside, restore,
};

/// `[post]`: what happens to the mesh after the engine. Defaults measured on cbd-small (21
/// frames) and cbd-large frame 23 at cell r/2 (issue 25).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PostConfig {
    /// Keep the field's exact isosurface: no smoothing, no volume restoration (the meshes of
    /// splash before post-processing, byte for byte).
    pub raw: bool,
    /// λ|μ pairs of Taubin smoothing before the volume rounds, each of which smooths by one
    /// pair too (default 0). Each pair first adds flicker to a sequence (issue 38, carried
    /// jitter with 0, 2 and 6 after `relax_first`: dense-dambreak 0.0264, 0.0269, 0.0297 r, A
    /// 0.0104, 0.0105, 0.0110 r, B 0.0266, 0.0267, 0.0270 r) for next to no smoothness:
    /// bumpiness the same on those three and on cbd-small (1.69°), cbd-large f23 2.32°, 2.31°,
    /// 2.29°.
    pub smoothing_iterations: u32,
    /// Taubin's shrinking factor λ (default 0.6, above Taubin 1995's 0.33 to 0.5: cbd-large f23
    /// 2.70° against 2.85° at 0.5 with the same pass-band).
    pub lambda: f32,
    /// Taubin's inflating factor μ, below −λ (default −0.64: pass-band k_PB = 1/λ + 1/μ ≈ 0.10,
    /// Taubin 1995's 0.1).
    pub mu: f32,
    /// Tangential relaxation steps before the smoothing (default 4), which even out Marching
    /// Cubes' triangles so that the smoothing's umbrella steps move the surface alike however
    /// the grid cut it (issue 38, with 6 smoothing pairs first: carried jitter on
    /// dense-dambreak 0.0316 → 0.0297 r, on A 0.0115 → 0.0110 r, on B 0.0277 → 0.0270 r;
    /// cbd-large f23 2.36° → 2.29°, slivers 0.019 → 0.016 %; without them, dense-dambreak
    /// 0.0686 → 0.0264 r; 8 or 12 steps do no better). The raw places, which faces that would
    /// cross go back to, are the vertices before it.
    pub relax_first: u32,
    /// Rounds of one volume step and one λ|μ pair, so that smoothing heals what the offsets
    /// fold (default 4, with `max_offset = 0.5`; 0 with `volume_steps = 0` keeps the volume).
    /// Against 8 rounds of 0.25 r (issue 38, carried jitter): dense-dambreak 0.0264 → 0.0256 r,
    /// A 0.0104 → 0.0101 r, B 0.0266 → 0.0262 r; bumpiness 4.53° → 4.60°, 1.14° → 1.15°,
    /// 2.00°, cbd-small 1.69° → 1.70°, cbd-large f23 2.32° → 2.40°, slivers 0.01 %; 0.97× the
    /// wall on f23. 6 rounds of 0.35 r lie between (0.0260 r, f23 2.35°).
    pub volume_rounds: u32,
    /// What the volume steps bring to N·r³: `"frame"` (default) the whole mesh, with one offset
    /// for every vertex, or `"component"` each closed component to the particles inside it.
    /// One offset moves the surface of a frame the same way its neighbours' move, where a
    /// droplet's own target jumps with its particle count and its offset with its shape: on
    /// dense-dambreak (issue 38) the jitter drops from 0.075 r to 0.060 r and the crossing faces
    /// from 117,063 to 7,114 in 40 frames; a droplet then keeps its share of the frame's
    /// inflation or shrinkage instead of exactly its particles' volume.
    pub volume_scope: VolumeScope,
    /// Largest offset of a volume step, in spacings r (default 0.5: cbd-large f23 needs 0.86 r
    /// in all; the relaxation before and after leaves 0.01 % slivers there).
    pub max_offset: f32,
    /// Bisect the edges whose two triangles meet at more than this angle, in degrees, after the
    /// volume rounds (default 0: never). The edges bisected differ from frame to frame, so a
    /// sequence flickers (issue 38: jitter on dense-dambreak 0.047 r without, 0.060 r with 16;
    /// on two simulated scenes 0.032 → 0.049 r and 0.108 → 0.161 r). 16 takes cbd-large f23
    /// from 2.66° to 1.96° and cbd-small from 1.65° to 1.40° for 26 % and 20 % more triangles,
    /// rims and droplets no longer faceted, for about 1.17× the wall time.
    pub refine_angle: f32,
    /// Tangential relaxation steps after the volume rounds and the refinement (default 12:
    /// slivers on cbd-large f23 0.46 %, 0.40 % with 15; without refinement 10 took them from
    /// 1.29 % to 0.39 %).
    pub relax_iterations: u32,
    /// Final volume steps, which bring each component within a fraction of a percent of its
    /// target (default 1: the rounds leave little to do, cbd-large f23 −0.12 % with 0, −0.11 %
    /// with 1 to 3; cbd-small ±0.0 %).
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
    /// In a sequence, average each frame's field with its neighbours' where the fluid's motion
    /// carries each vertex, and move its surface towards their surfaces carried to its time
    /// (default false): a low-pass in time along the flow (issue 38). Frames without both
    /// neighbours (a lone file, the ends of a sequence, a gap, a neighbour that fails) are
    /// meshed and post-processed alone. Not with `raw`. Experimental: carried jitter against
    /// the default's on dense-dambreak 0.0224 → 0.0143 r, on B2 (a ball thrown into a pool)
    /// 0.0184 → 0.0124 r, for 1.4–1.6× the wall time (B2 1.37×, dense-dambreak 1.51–1.58×,
    /// two pinned cores), short of the cost target.
    pub temporal: bool,
    /// Seconds between frames, to carry particles by their velocity when the files have no
    /// particle ids (default none: such sequences are post-processed frame by frame).
    pub frame_time: Option<f32>,
}

impl Default for PostConfig {
    fn default() -> Self {
        PostConfig {
            raw: false,
            smoothing_iterations: 0,
            lambda: 0.6,
            mu: -0.64,
            relax_first: 4,
            volume_rounds: 4,
            volume_scope: VolumeScope::Frame,
            max_offset: 0.5,
            refine_angle: 0.0,
            relax_iterations: 12,
            volume_steps: 1,
            mesh_aabb: None,
            min_component: None,
            decimate: None,
            temporal: false,
            frame_time: None,
        }
    }
}

impl PostConfig {
    /// Whether [`postprocess`] would change a mesh: false only for `raw` without a box, a
    /// smallest component or a decimation.
    pub fn changes_mesh(&self) -> bool {
        // `temporal` needs neighbours: a sequence's, not a frame's, concern.
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
        if !(self.refine_angle >= 0.0 && self.refine_angle < 180.0) {
            bail_config!(
                "post.refine_angle ({}) must lie in [0, 180) degrees (0: no refinement)",
                self.refine_angle
            );
        }
        if let Some(dt) = self.frame_time
            && !(dt.is_finite() && dt > 0.0)
        {
            bail_config!("post.frame_time ({dt}) must be a positive number of seconds");
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
/// threads. The mesh is trusted to be an engine's (closed, manifold, indices in range): see
/// [`postprocess_mesh`] for a mesh from elsewhere.
pub fn postprocess(
    mesh: &mut TriMesh,
    particles: &[Vec3],
    spacing: f32,
    cell: f32,
    config: &PostConfig,
    normals: bool,
) -> Result<()> {
    let volumes = Volumes::Particles { particles, cell };
    stages(mesh, spacing, &volumes, config, normals).map(drop)
}

/// What [`postprocess_mesh`] brings the volume to: with particles, the whole mesh's or each
/// closed component's ([`PostConfig::volume_scope`]); without, each component's own.
#[derive(Debug, Clone, Copy)]
pub enum Volumes<'a> {
    /// N_c·r³ for the N_c of `particles` inside each component, summed over the mesh for
    /// [`VolumeScope::Frame`] (by ray parity; `cell` sizes the
    /// rays' bins and their tiny shift off the grid planes: pass the reconstruction's cell to
    /// get its bytes). Components holding none, and cavities, keep their own volume.
    Particles {
        /// The particles the mesh encloses.
        particles: &'a [Vec3],
        /// The Marching Cubes cell of the reconstruction, in world units.
        cell: f32,
    },
    /// The volume the component enclosed before smoothing: volume-true smoothing of any mesh.
    Kept,
}

/// [`postprocess`] for a mesh from anywhere: each closed component's volume brought to
/// `volumes`, lengths of `config` (`max_offset`, `decimate`, `min_component`) in units of
/// `spacing`. The mesh must be closed, manifold and consistently wound (each edge shared by
/// exactly two triangles that walk it in opposite directions), as every mesh splash writes:
/// the volume of an open surface, its inside for the particles' rays, and the caps of a box
/// are not defined. Triangles that repeat a vertex are allowed (they enclose nothing).
/// `normals`: whether the result gets vertex normals (area-weighted where the vertices
/// moved).
///
/// Errors ([`Error::Input`], naming what is wrong): triangles referencing missing vertices,
/// non-finite vertices or particles, normals neither absent nor one per vertex, a surface with
/// boundary, non-manifold or inconsistently wound edges (counted); [`Error::Config`]: a
/// `spacing` or `cell` that is not a positive finite length, or a `config` out of range;
/// [`Error::Limit`]: a mesh beyond 2^31 vertices.
pub fn postprocess_mesh(
    mesh: &mut TriMesh,
    spacing: f32,
    volumes: Volumes<'_>,
    config: &PostConfig,
    normals: bool,
) -> Result<()> {
    config.validate()?;
    if !(spacing.is_finite() && spacing > 0.0) {
        bail_config!("the spacing ({spacing}) must be a positive finite length");
    }
    if let Volumes::Particles { particles, cell } = volumes {
        if !(cell.is_finite() && cell > 0.0) {
            bail_config!("the cell ({cell}) must be a positive finite length");
        }
        if let Some(i) = particles.iter().position(|p| !p.is_finite()) {
            return Err(Error::input(format!(
                "particle {i} has a non-finite coordinate"
            )));
        }
    }
    validate(mesh)?;
    if mesh.vertices.len() > 1 << 31 {
        return Err(Error::limit(format!(
            "mesh of {} vertices is too large to check (at most 2^31)",
            mesh.vertices.len()
        )));
    }
    let t = topology(mesh);
    if !t.is_closed_manifold() {
        return Err(Error::input(format!(
            "the mesh is not closed and consistently wound: {} boundary edges (used by one \
             triangle), {} non-manifold edges (by three or more), {} edges whose two triangles \
             wind the same way; post-processing needs the surface of a solid",
            t.boundary_edges, t.non_manifold_edges, t.inconsistent_edges
        )));
    }
    if !normals {
        mesh.normals = Vec::new();
    } else if mesh.normals.is_empty() && config.raw {
        // Smoothing would compute them; the raw path's stages keep the ones there are.
        mesh.normals = crate::mesh::stars::area_weighted_normals(&mesh.vertices, &mesh.triangles);
    }
    stages(mesh, spacing, &volumes, config, normals).map(drop)
}

/// The stages of [`postprocess`] and [`postprocess_mesh`], returning which vertices of the
/// mesh have another side of the surface facing them within the clearance's reach (where a
/// later move can make faces cross: the guard of following the fluid tests their faces), or
/// None where it did not look (`raw`) or changed the vertices after looking (the box, the small
/// components, the decimation).
pub(crate) fn stages(
    mesh: &mut TriMesh,
    spacing: f32,
    volumes: &Volumes<'_>,
    config: &PostConfig,
    normals: bool,
) -> Result<Option<Vec<bool>>> {
    let mut close = None;
    if !config.raw {
        close = Some(smooth_and_restore(mesh, volumes, spacing, config, normals));
    }
    // Clipped after smoothing, so that the caps stay flat; components dropped after clipping,
    // which can leave small pieces; decimated last, against the mesh that would be written.
    if config.mesh_aabb.is_some() || config.min_component.is_some() || config.decimate.is_some() {
        close = None;
    }
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
    Ok(close)
}

/// Smooths `mesh` and restores its volume (see the module's header). Keeps the
/// topology; moves the vertices, bisects the edges where the surface bends (when
/// `refine_angle` is set) and recomputes the normals (when the mesh has normals). Returns
/// which vertices have another side facing them within the clearance's reach.
fn smooth_and_restore(
    mesh: &mut TriMesh,
    volumes: &Volumes<'_>,
    spacing: f32,
    config: &PostConfig,
    wants_normals: bool,
) -> Vec<bool> {
    if mesh.triangles.is_empty() {
        return vec![false; mesh.vertices.len()];
    }
    let TriMesh {
        vertices,
        normals,
        triangles,
    } = mesh;
    let mut rings = Neighbours::new(VertexFaces::new(vertices.len(), triangles), triangles);
    let (lambda, mu) = (config.lambda, config.mu);
    // One buffer is the smoothing's scratch (a vertex each) and the measures' triangle normals
    // (a triangle each), in turn.
    let mut measures = Measures::default();
    measures.scratch(triangles.len().max(vertices.len()));
    if normals.len() != vertices.len() {
        // Zeroed pages rather than a fill on one thread: every normal is written before use.
        *normals = vec![Vec3::ZERO; vertices.len()];
    }
    let scratch = measures.scratch(vertices.len());
    // The component labels and the raw volumes, walks on one thread, read the raw vertices
    // while the first relaxation and smoothing run on a copy in the rest of the pool.
    let ((mut components, raw_volumes), smoothed) = rayon::join(
        || {
            let components = Components::new(&rings);
            let volumes = components.volumes_and_areas(vertices, triangles);
            (components, volumes)
        },
        || {
            let mut smoothed = vertices.clone();
            if config.relax_first > 0 {
                vertex_normals(vertices, triangles, rings.faces(), normals);
                relax_tangentially(
                    &mut smoothed,
                    scratch,
                    normals,
                    &rings,
                    config.relax_first,
                    RELAX_STEP,
                );
            }
            taubin(
                &mut smoothed,
                scratch,
                &rings,
                config.smoothing_iterations,
                lambda,
                mu,
            );
            smoothed
        },
    );
    // The raw places, for the faces that the smoothing and the volume steps make cross.
    let raw = std::mem::replace(vertices, smoothed);
    normals_and_measures(
        vertices,
        triangles,
        rings.faces(),
        &components,
        normals,
        &mut measures,
    );

    let targets: Vec<f64> = match volumes {
        _ if config.volume_rounds + config.volume_steps == 0 => Vec::new(),
        Volumes::Particles { particles, cell } => {
            let inside = particles_inside(
                &components,
                &raw_volumes,
                vertices,
                triangles,
                particles,
                *cell,
            );
            let r3 = f64::from(spacing).powi(3);
            // Bubbles (negative volume) and blobs without a particle keep their raw volume.
            raw_volumes
                .iter()
                .zip(&inside)
                .map(|(&(v, _), &n)| if v > 0.0 && n > 0 { n as f64 * r3 } else { v })
                .collect()
        }
        Volumes::Kept => raw_volumes.iter().map(|&(v, _)| v).collect(),
    };
    // A mesh's own volumes do not jump from frame to frame as particle counts do: each
    // component keeps its own.
    let scope = match volumes {
        Volumes::Particles { .. } => config.volume_scope,
        Volumes::Kept => VolumeScope::Component,
    };
    let max_step = config.max_offset * spacing;
    let mut clearance = clearance(
        vertices,
        normals,
        &rings,
        &components.of_vertex,
        &raw_volumes,
        &targets,
        scope,
        spacing,
    );
    for _ in 0..config.volume_rounds {
        let scratch = measures.scratch(vertices.len());
        taubin(vertices, scratch, &rings, 1, lambda, mu);
        restore(
            vertices,
            normals,
            &mut measures,
            triangles,
            rings.faces(),
            &components,
            &targets,
            scope,
            &mut clearance,
            1,
            max_step,
        );
    }
    // The normals for the refinement and the relaxation.
    vertex_normals(vertices, triangles, rings.faces(), normals);
    let mut parents = Vec::new();
    if config.refine_angle > 0.0 {
        // Made anew at the refined size; the refinement's own arrays take their place.
        measures = Measures::default();
        parents = refine_bends(
            vertices,
            normals,
            triangles,
            std::mem::take(&mut rings).into_faces(),
            config.refine_angle.to_radians(),
        );
        rings = Neighbours::new(VertexFaces::new(vertices.len(), triangles), triangles);
        // A new vertex joins its edge's component and takes its room; the numbering stays.
        components.of_vertex.reserve_exact(parents.len());
        for &p in &parents {
            components.of_vertex.push(components.of_vertex[p as usize]);
        }
        clearance.extend(parents.iter().copied());
        debug_assert_eq!(components.of_vertex.len(), vertices.len());
    }
    let scratch = measures.scratch(vertices.len());
    relax_tangentially(
        vertices,
        scratch,
        normals,
        &rings,
        config.relax_iterations,
        RELAX_STEP,
    );
    let rings = rings.into_faces();
    restore(
        vertices,
        normals,
        &mut measures,
        triangles,
        &rings,
        &components,
        &targets,
        scope,
        &mut clearance,
        config.volume_steps,
        max_step,
    );
    let close = clearance.into_close();
    uncross(vertices, triangles, raw, &parents, &close);
    if wants_normals {
        normals_and_measures(
            vertices,
            triangles,
            &rings,
            &components,
            normals,
            &mut measures,
        );
    } else {
        *normals = Vec::new();
    }
    close
}

/// The share of its ring's tangential pull a vertex moves by in a relaxation step, before the
/// smoothing and after the volume steps alike.
const RELAX_STEP: f32 = 0.5;

/// What the volume steps leave between two sides that close in on each other, in spacings r:
/// 0.15 r each, so that a sheet keeps 0.3 r (crossing faces on cbd-large f23 7,382 with 0.05,
/// 2,788 with 0.15; cbd-small 14 and 0).
const MARGIN: f32 = 0.15;

/// The [`Clearance`] of the smoothed mesh for the volume steps towards `targets` from the raw
/// `volumes` (and areas), by `scope`: it looks as far as the offset those need, at most 2r.
#[allow(clippy::too_many_arguments)]
fn clearance(
    vertices: &[Vec3],
    normals: &[Vec3],
    rings: &Neighbours,
    of_vertex: &[u32],
    volumes: &[(f64, f64)],
    targets: &[f64],
    scope: VolumeScope,
    spacing: f32,
) -> Clearance {
    let offsets = if targets.is_empty() {
        vec![0.0; volumes.len()]
    } else {
        first_order_offsets(volumes, targets, scope)
    };
    let margin = MARGIN * spacing;
    let largest = offsets.iter().fold(0.0f32, |m, o| m.max(o.abs()));
    // Two sides that close in on each other meet within twice the offset; cells of at least
    // r/2 keep the grid's cells few where the offset is small.
    let reach = (2.0 * (1.5 * largest + margin)).clamp(0.5 * spacing, 2.0 * spacing);
    let towards = offsets
        .iter()
        .map(|&o| if o == 0.0 { 0.0 } else { o.signum() })
        .collect();
    Clearance::new(vertices, normals, rings, of_vertex, towards, reach, margin)
}
