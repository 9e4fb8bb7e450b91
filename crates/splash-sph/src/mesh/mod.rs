//! Triangle meshes: the output of every engine.

pub mod adjacency;
pub mod components;
pub mod correction;
pub mod edges;
pub(crate) mod marching_cubes;
pub mod post;
pub mod quality;
pub mod self_intersections;
pub mod signed_distance;
mod stars;
pub mod topology;

pub use components::drop_small_components;
pub use post::clipping::clip_to_box;
pub use post::decimation::decimate;
pub use post::volume::VolumeScope;
pub use self_intersections::self_intersecting_faces;
pub use signed_distance::SignedDistance;
pub(crate) use stars::area_weighted_normals;

#[doc(no_inline)]
pub use crate::data::TriMesh;
