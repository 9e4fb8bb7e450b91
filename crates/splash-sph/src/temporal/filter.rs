//! Surfaces that follow the fluid from frame to frame (issue 38): [`follow_fluid`], by the
//! method [`Followed`] describes.

use glam::Vec3;
use rayon::prelude::*;

use super::motion::{FrameMotion, mean_motions};
use crate::error::Result;
use crate::mesh::post::put_back_near;
use crate::mesh::{
    Cursor, SignedDistance, SurfaceBins, TriMesh, area_normal, area_weighted_normals,
};

/// Frame t's neighbours for [`follow_fluid`]: a neighbour frame's mesh and particles.
#[derive(Debug, Clone, Copy)]
pub struct Neighbour<'a> {
    /// The neighbour's mesh, post-processed as frame t's was.
    pub mesh: &'a TriMesh,
    /// Its triangles binned by [`neighbour_bins`] (a sequence keeps them for both frames
    /// beside it).
    pub bins: &'a SurfaceBins,
    /// The neighbour's particles, which frame t's are matched with.
    pub motion: &'a FrameMotion,
}

/// What following the fluid did to a frame's surface (`post.temporal` in a sequence,
/// [`surface_following`](crate::pipeline::surface_following) for frames in memory).
///
/// Each vertex of frame t's mesh is moved along its normal to the mean of where the surfaces
/// of frames t−1, t and t+1 lie once carried to time t by the fluid's own motion (the kernel
/// mean of the particles' displacements around the vertex, support 2r; a vertex with no
/// particle that near keeps its place), the neighbours weighing a little more than the frame
/// itself (0.4 each, 0.2 for frame t).
/// Where the fluid carries the surface as it moves, the neighbours agree with frame t and
/// nothing moves; what jumps at one frame alone is shared with its neighbours, a low-pass in
/// time along the flow (the explicit surfaces of Yu, Wojtan, Turk & Yap 2012 follow the fluid
/// in the same sense). A neighbour's surface weighs less the farther it lies from the carried
/// vertex, smoothly down to nothing at 3r (a topology change, a droplet that left), and
/// no vertex moves farther than 0.2 r, so that no surface is pulled into another.
/// Where faces cross after all, their vertices and a ring around them keep their own frame's
/// places.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Followed {
    /// Vertices moved.
    pub moved: usize,
    /// Root mean square and largest move, in world units.
    pub rms: f64,
    /// The largest move.
    pub max: f32,
}

/// `close` with the corners of every face folded against a corner's normal (its normal
/// pointing away from the mean of the faces there): a crumpled rim, where adjacent faces lie
/// back to back and the smallest move along the normals makes them cross (4 faces of
/// dense-dambreak frame 155 with the fields averaged along the flow, none close).
fn with_folds(
    close: &[bool],
    triangles: &[[u32; 3]],
    vertices: &[Vec3],
    normals: &[Vec3],
) -> Vec<bool> {
    let folded: Vec<&[u32; 3]> = triangles
        .par_iter()
        .filter(|t| {
            let n = area_normal(t, vertices);
            t.iter().any(|&v| normals[v as usize].dot(n) < 0.0)
        })
        .collect();
    let mut out = close.to_vec();
    for &v in folded.into_iter().flatten() {
        out[v as usize] = true;
    }
    out
}

/// A neighbour's mesh binned for [`follow_fluid`] at spacing `spacing` (r).
pub fn neighbour_bins(mesh: &TriMesh, spacing: f32) -> SurfaceBins {
    SurfaceBins::new(&mesh.vertices, &mesh.triangles, REACH * spacing)
}

/// Each neighbour's share of the mean. Measured with the fields averaged along the flow (each
/// side then weighing 1/3 there), reach 3r (`splash bench temporal`, carried jitter,
/// dense-dambreak 120–135 and B2): 0.4 gives 0.0159 and 0.0119 r, 1/3 (the three frames
/// alike) 0.0159 and 0.0123 r, 0.45 0.0162 and 0.0118 r. Before the fields were averaged,
/// 1/3 had read 0.0182 r on dense-dambreak against 0.0197 r with the binomial's 1/4 and
/// 0.0206 r with 1/2 (the neighbours alone).
const WEIGHT: f32 = 0.4;

/// How far, in spacings r, a neighbour's surface may lie from the carried vertex and still
/// count: its weight falls as (1 − (e/reach)²)² to nothing there. With weight 1/3, carried
/// jitter on dense-dambreak 120–135 and B2: reach r 0.0166 and 0.0135 r, 1.5r 0.0165 and
/// 0.0126 r, 2r 0.0163 and 0.0124 r, 3r 0.0159 and 0.0123 r, 4r (weight 0.4) as 3r. A vertex
/// whose neighbours' surfaces lie between r and 3r away (a droplet that splits off, a sheet
/// that tears) eases into the change over the frames instead of jumping at one.
const REACH: f32 = 3.0;

/// The farthest a vertex moves, in spacings r: less than half the post-processing's clearance
/// (at least r/2), so that two sides of the surface that do not face each other within it
/// cannot meet. Capped at 0.2r (the field mean's sides then at 1/3), carried jitter on
/// dense-dambreak 120–135 reads 0.0164 r against 0.0159 r uncapped, B2 0.0119 r either way.
const MAX_MOVE: f32 = 0.2;

/// Moves the vertices of `mesh` (frame t, with `own` its particles) towards the surfaces of
/// `neighbours` (frames t−1 and t+1) carried to time t by the displacements of `own`'s
/// particles to each (matched by id, else velocity × `frame_time`), as [`Followed`] says, and
/// recomputes its normals when it has them: [`carry`], then [`follow_carried`]. None, with
/// nothing moved, when the particles cannot be carried (no ids, and no velocities with a frame
/// time).
pub fn follow_fluid(
    mesh: &mut TriMesh,
    close: &[bool],
    own: &FrameMotion,
    neighbours: [Neighbour<'_>; 2],
    frame_time: Option<f32>,
    spacing: f32,
    cell: f32,
) -> Result<Option<Followed>> {
    let motions = neighbours.map(|n| n.motion);
    let Some(carried) = carry(mesh, own, motions, frame_time, spacing, cell)? else {
        return Ok(None);
    };
    let surfaces = neighbours.map(|n| (n.mesh, n.bins));
    Ok(Some(follow_carried(
        mesh, close, carried, surfaces, spacing, cell,
    )))
}

/// Frame t's vertices as [`carry`] carries them to the frames beside it.
pub struct Carried {
    /// The mesh's area-weighted normals.
    normals: Vec<Vec3>,
    /// Per side (t−1, t+1), the fluid's mean displacement at each vertex, if a particle is
    /// near enough to tell.
    motions: Vec<Vec<Option<Vec3>>>,
}

/// Where the fluid carries the vertices of `mesh` (frame t, `own` its particles) to the times
/// of the frames whose particles are `sides` (t−1, t+1): the kernel mean (support 2r,
/// `spacing` r) of the displacements of `own`'s particles, matched by id, else velocity ×
/// `frame_time`. None when the particles cannot be carried.
pub fn carry(
    mesh: &TriMesh,
    own: &FrameMotion,
    sides: [&FrameMotion; 2],
    frame_time: Option<f32>,
    spacing: f32,
    cell: f32,
) -> Result<Option<Carried>> {
    let (Some(back), Some(ahead)) = (
        own.displacements(sides[0], -1, frame_time),
        own.displacements(sides[1], 1, frame_time),
    ) else {
        return Ok(None);
    };
    if mesh.triangles.is_empty() {
        return Ok(Some(Carried {
            normals: Vec::new(),
            motions: Vec::new(),
        }));
    }
    let normals = area_weighted_normals(&mesh.vertices, &mesh.triangles);
    let motions = mean_motions(
        &mesh.vertices,
        &own.positions,
        &[&back, &ahead],
        2.0 * spacing,
        cell,
    )?;
    Ok(Some(Carried { normals, motions }))
}

/// Moves the vertices of `mesh`, [`carry`]'s `carried`, towards the `surfaces` beside it (each
/// a mesh and its [`neighbour_bins`]) as [`Followed`] says. `spacing`: r; the neighbours count
/// within 3r. `close`: per vertex, whether another side of the surface faces it within the
/// post-processing's clearance (at least r/2: more than twice the farthest a vertex moves
/// here, 0.2 r); with cells up to r only their faces and those near a fold are tested for
/// crossings, as the post-processing's guard tests them, else (empty, or larger cells) every
/// face.
pub fn follow_carried(
    mesh: &mut TriMesh,
    close: &[bool],
    carried: Carried,
    surfaces: [(&TriMesh, &SurfaceBins); 2],
    spacing: f32,
    cell: f32,
) -> Followed {
    if mesh.triangles.is_empty() {
        return Followed::default();
    }
    let Carried { normals, motions } = carried;
    let reach = REACH * spacing;
    let mut offsets = vec![0.0f32; mesh.vertices.len()];
    for ((side, bins), carried) in surfaces.iter().zip(&motions) {
        let surface = SignedDistance::with_bins(&side.vertices, &side.triangles, bins);
        offsets
            .par_iter_mut()
            .zip(&mesh.vertices)
            .zip(carried)
            .for_each_init(Cursor::default, |cursor, ((offset, &x), &a)| {
                // Where no particle says how the fluid moves, the vertex keeps its place.
                let Some(a) = a else { return };
                if let Some(e) = surface.at_from(x + a, cursor) {
                    let taper = (1.0 - (e / reach).powi(2)).max(0.0);
                    *offset -= WEIGHT * e * taper * taper;
                }
            });
    }
    let own = mesh.vertices.clone();
    mesh.vertices
        .par_iter_mut()
        .zip(&normals)
        .zip(&mut offsets)
        .for_each(|((x, n), offset)| {
            // A vertex without a normal (its faces enclose nothing) stays, and counts as
            // unmoved.
            if *n == Vec3::ZERO {
                *offset = 0.0;
            } else {
                *offset = offset.clamp(-MAX_MOVE * spacing, MAX_MOVE * spacing);
                *x += *n * *offset;
            }
        });
    // Where following made faces cross (two sheets pulled towards different neighbours'
    // surfaces), their corners and a ring keep their own frame's places.
    // Measured against testing every face, the same meshes at r/2 and r (dense-dambreak's 40
    // frames, B2's 30, cbd-small's 21); at 2r, where faces are as wide as the clearance's
    // reach, 4 crossing faces in 3 of dense-dambreak's 40 frames, so there every face is tested.
    let close = (close.len() == own.len() && cell <= spacing)
        .then(|| with_folds(close, &mesh.triangles, &own, &normals));
    let close = close.as_deref();
    let went_back = put_back_near(&mut mesh.vertices, &mesh.triangles, &own, close);
    for (offset, _) in offsets.iter_mut().zip(&went_back).filter(|(_, b)| **b) {
        *offset = 0.0;
    }
    let mut followed = Followed::default();
    let mut squares = 0.0f64;
    for &offset in offsets.iter().filter(|&&o| o != 0.0) {
        followed.moved += 1;
        squares += f64::from(offset) * f64::from(offset);
        followed.max = followed.max.max(offset.abs());
    }
    followed.rms = (squares / mesh.vertices.len() as f64).sqrt();
    if !mesh.normals.is_empty() {
        mesh.normals = area_weighted_normals(&mesh.vertices, &mesh.triangles);
    }
    followed
}
