//! One frame's surface from particles in memory: reconstruction (Akinci et al. 2012,
//! Algorithm 1) with the mesh's post-processing (`[post]`, run by the reconstructor), then the
//! particle attributes interpolated onto the final vertices. The file pipeline ([`FramePipeline`](super::FramePipeline)) and
//! the Python binding both go through it.

use std::time::{Duration, Instant};

use glam::Vec3;

use crate::error::Result;
use crate::io::Attribute;
use crate::mesh::TriMesh;
use crate::reconstructor::Reconstructor;
use crate::report::{FrameStats, Observer};

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
