//! Triangle meshes: the output of every engine. Their post-processing ([`post`]: smoothing,
//! volume, [`clip_to_box`], [`drop_small_components`], [`decimate`]), and their measures:
//! [`topology`] (closed and manifold, components, enclosed volume), [`quality`] (the render
//! figures of issue 25), [`self_intersecting_faces`], [`SignedDistance`] and [`Edges`].

pub(crate) mod adjacency;
mod components;
pub(crate) mod correction;
mod edges;
pub(crate) mod facing;
pub(crate) mod marching_cubes;
pub mod post;
pub(crate) mod quality;
mod self_intersections;
pub(crate) mod signed_distance;
mod stars;
pub(crate) mod topology;

pub(crate) use components::component_labels_and_volumes;
pub use components::drop_small_components;
pub use edges::Edges;
pub use post::{VolumeScope, clip_to_box, decimate};
pub use quality::{Quality, SLIVER_DEGREES, SMALL_COMPONENT_FACES, quality, volume_error};
pub use self_intersections::self_intersecting_faces;
pub use signed_distance::{Cursor, SignedDistance, SurfaceBins};
pub(crate) use stars::{area_normal, area_weighted_normals, unit_normal};
pub use topology::{Topology, component_volumes, signed_volume, topology};

#[doc(no_inline)]
pub use crate::data::TriMesh;

/// The cells of the box from `lo` to `hi`, both included, z slowest: the grid walks of the
/// binned searches (signed distances, following's crossing test, the level set's scan).
pub(crate) fn cells_between(lo: glam::IVec3, hi: glam::IVec3) -> impl Iterator<Item = glam::IVec3> {
    (lo.z..=hi.z).flat_map(move |z| {
        (lo.y..=hi.y).flat_map(move |y| (lo.x..=hi.x).map(move |x| glam::IVec3::new(x, y, z)))
    })
}
