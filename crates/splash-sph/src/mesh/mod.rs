//! Triangle meshes: the output of every engine.

pub mod adjacency;
pub mod clearance;
pub mod clipping;
pub mod components;
pub mod correction;
pub mod decimation;
pub mod edges;
pub(crate) mod marching_cubes;
pub mod post;
pub mod quality;
pub mod refinement;
pub mod self_intersections;
pub mod signed_distance;
pub mod smoothing;
mod stars;
pub mod topology;
pub mod volume;

pub use clipping::clip_to_box;
pub use components::drop_small_components;
pub use decimation::decimate;
pub use self_intersections::self_intersecting_faces;
pub use signed_distance::SignedDistance;
pub(crate) use stars::area_weighted_normals;
pub use volume::VolumeScope;

#[doc(no_inline)]
pub use crate::data::TriMesh;
