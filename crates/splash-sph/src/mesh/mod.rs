//! Triangle meshes: the output of every engine.

pub mod adjacency;
pub mod clipping;
pub mod components;
pub mod correction;
pub mod decimation;
pub mod edges;
pub(crate) mod marching_cubes;
pub mod post;
pub mod quality;
pub mod refinement;
pub mod signed_distance;
pub mod smoothing;
mod stars;
pub mod topology;
pub mod volume;

pub use clipping::clip_to_box;
pub use components::drop_small_components;
pub use decimation::decimate;
pub use signed_distance::SignedDistance;
pub(crate) use stars::area_weighted_normals;

use glam::Vec3;

/// An indexed triangle mesh with one normal per vertex; triangles wind counter-clockwise seen
/// from outside the fluid.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TriMesh {
    /// Vertex positions.
    pub vertices: Vec<Vec3>,
    /// One unit normal per vertex, pointing out of the fluid; empty when none were asked for.
    pub normals: Vec<Vec3>,
    /// Indices into `vertices`, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
}

impl TriMesh {
    /// Whether the mesh has no triangles.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// Bytes held by the mesh's arrays.
    pub fn heap_bytes(&self) -> usize {
        self.vertices.capacity() * size_of::<Vec3>()
            + self.normals.capacity() * size_of::<Vec3>()
            + self.triangles.capacity() * size_of::<[u32; 3]>()
    }
}
