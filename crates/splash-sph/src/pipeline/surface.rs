//! One frame's surface from particles in memory: reconstruction (Akinci et al. 2012,
//! Algorithm 1) with the mesh's post-processing (`[post]`, run by the reconstructor), then the
//! particle attributes interpolated onto the final vertices. The file pipeline ([`FramePipeline`](super::FramePipeline)) and
//! the Python binding both go through it; [`surface_following`] does the same for a frame whose
//! neighbouring frames the caller holds, its surface following the fluid (issue 38).

use std::time::{Duration, Instant};

use glam::Vec3;

use crate::error::{Error, Result};
use crate::io::Attribute;
use crate::mesh::TriMesh;
use crate::recon::Sides;
use crate::reconstructor::Reconstructor;
use crate::report::{FrameStats, Observer};
use crate::temporal::{Followed, FrameMotion, Neighbour, follow_fluid, neighbour_bins};

/// A frame's surface: its mesh, the attributes asked for (one value per vertex each, in the
/// order asked), and its figures.
#[derive(Debug, Clone)]
pub struct Surface {
    /// The closed, outward-oriented mesh.
    pub mesh: TriMesh,
    /// The interpolated attributes, one per attribute asked for.
    pub attributes: Vec<Attribute>,
    /// Counts, array bytes, and the stage figures `observer` measured.
    pub stats: FrameStats,
    /// Wall time of the attributes' interpolation.
    pub interpolation: Duration,
}

/// The surface of `positions` with `attributes` (one value per particle each) carried onto its
/// vertices through one neighbour search; `observer` measures the reconstruction's stages.
pub fn surface(
    reconstructor: &Reconstructor,
    positions: &[Vec3],
    attributes: &[&Attribute],
    observer: &mut dyn Observer,
) -> Result<Surface> {
    let rec = reconstructor
        .reconstruct_observed(positions, observer)
        .map_err(|e| e.context("reconstruction failed"))?;
    let mesh = rec.mesh;
    // The reconstructor has post-processed the mesh (`[post]`), so the attributes are carried
    // onto the vertices that are written.
    let start = Instant::now();
    let attributes = reconstructor.interpolate_all(&mesh, positions, attributes)?;
    Ok(Surface {
        mesh,
        attributes,
        stats: rec.stats,
        interpolation: start.elapsed(),
    })
}

/// One frame's particles with their ids, for [`surface_following`].
#[derive(Debug, Clone, Copy)]
pub struct FrameParticles<'a> {
    /// Positions.
    pub positions: &'a [Vec3],
    /// Each particle's identity across frames (unique).
    pub ids: &'a [u32],
}

/// The [`surface`] of frame t (`frames[1]`), its field averaged with those of frames t−1 and
/// t+1 (`frames[0]`, `frames[2]`) where their particles, matched by id, carry each vertex, and
/// moved towards their surfaces carried to its time (what `post.temporal` does in a sequence,
/// where the neighbours' fields are averaged too; see [`Followed`]), with `attributes` (one
/// value per particle of frame t) interpolated onto the moved vertices. The three frames are
/// reconstructed (so about three times the work of [`surface`]); `observer` measures frame
/// t's stages. Particles of frame t missing from a neighbour do not carry it. With
/// `post.raw` the neighbours are not followed: [`Followed`] says nothing moved.
///
/// Errors: those of [`surface`] for any of the three frames, [`Error::Input`] for ids that
/// repeat or do not match their positions' count (naming the frame).
pub fn surface_following(
    reconstructor: &Reconstructor,
    frames: [FrameParticles<'_>; 3],
    attributes: &[&Attribute],
    observer: &mut dyn Observer,
) -> Result<(Surface, Followed)> {
    const NAMES: [&str; 3] = ["the frame before", "the frame", "the frame after"];
    let motions = frames
        .iter()
        .zip(NAMES)
        .map(|(f, name)| {
            FrameMotion::with_ids(f.positions.to_vec(), f.ids.to_vec())
                .map_err(|e| Error::input(format!("{name}: {e}")))
        })
        .collect::<Result<Vec<_>>>()?;
    let own = &motions[1];
    let follows = !reconstructor.config().post.raw;
    let moves = follows.then(|| {
        [0, 2].map(|k| {
            own.displacements(&motions[k], k as i32 - 1, None)
                .expect("frames with ids carry their particles")
        })
    });
    // Each frame's field sampled once: frame t's surface is made from its own, averaged
    // with the others', and the neighbours' surfaces from theirs.
    let fields = motions
        .iter()
        .zip(NAMES)
        .map(|(m, name)| {
            let observed: Option<&mut dyn Observer> = (name == NAMES[1]).then_some(&mut *observer);
            reconstructor
                .sample(&m.positions, observed)
                .map_err(|e| e.context(format!("reconstruction of {name} failed")))
        })
        .collect::<Result<Vec<_>>>()?;
    let sides = moves.as_ref().and_then(|[back, ahead]| {
        Some(Sides {
            fields: [fields[0].as_ref()?, fields[2].as_ref()?],
            moves: [back, ahead],
        })
    });
    let rec = reconstructor
        .reconstruct_along_flow(
            &own.positions,
            fields[1].as_ref(),
            sides.as_ref(),
            Some(observer),
        )
        .map_err(|e| e.context("reconstruction failed"))?;
    let mut mesh = rec.mesh;
    let mut followed = Followed::default();
    if follows && !mesh.triangles.is_empty() {
        let side = |k: usize| -> Result<TriMesh> {
            Ok(reconstructor
                .reconstruct_along_flow(&motions[k].positions, fields[k].as_ref(), None, None)
                .map_err(|e| e.context(format!("reconstruction of {} failed", NAMES[k])))?
                .mesh)
        };
        let (spacing, cell) = (rec.stats.spacing, rec.stats.cell);
        let meshes = [side(0)?, side(2)?];
        let bins = [&meshes[0], &meshes[1]].map(|m| neighbour_bins(m, spacing));
        let neighbours = [0, 1].map(|k| Neighbour {
            mesh: &meshes[k],
            bins: &bins[k],
            motion: &motions[2 * k],
        });
        followed = reconstructor
            .install(|| follow_fluid(&mut mesh, &rec.close, own, neighbours, None, spacing, cell))?
            .expect("frames with ids carry their particles");
    }
    let start = Instant::now();
    let attributes = reconstructor.interpolate_all(&mesh, &own.positions, attributes)?;
    let surface = Surface {
        mesh,
        attributes,
        stats: rec.stats,
        interpolation: start.elapsed(),
    };
    Ok((surface, followed))
}
