//! Triangle meshes: the output of every engine. Their post-processing ([`post`]: smoothing,
//! volume, [`clip_to_box`], [`drop_small_components`], [`decimate`]), and their measures:
//! [`topology`] (closed and manifold, components, enclosed volume), [`quality`] (the render
//! figures of issue 25), [`self_intersecting_faces`], [`SignedDistance`] and [`Edges`].

pub(crate) mod adjacency;
mod components;
pub(crate) mod correction;
mod edges;
pub(crate) mod marching_cubes;
pub mod post;
pub(crate) mod quality;
mod self_intersections;
pub(crate) mod signed_distance;
mod stars;
pub(crate) mod topology;

pub use components::drop_small_components;
pub use edges::Edges;
pub use post::{VolumeScope, clip_to_box, decimate};
pub use quality::{Quality, SLIVER_DEGREES, SMALL_COMPONENT_FACES, quality, volume_error};
pub use self_intersections::self_intersecting_faces;
pub use signed_distance::{SignedDistance, SurfaceBins};
pub(crate) use stars::area_weighted_normals;
pub use topology::{Topology, component_volumes, signed_volume, topology};

#[doc(no_inline)]
pub use crate::data::TriMesh;

/// `p.floor().as_ivec3()` without a call into libm (the baseline x86-64 target has no SSE4.1
/// rounding): the cell of `p` in a grid of unit cells, saturating beyond i32's reach.
pub(crate) fn floor_cell(p: glam::Vec3) -> glam::IVec3 {
    glam::IVec3::from_array(p.to_array().map(floor_i32))
}

/// `x.floor() as i32`, without a call into libm.
pub(crate) fn floor_i32(x: f32) -> i32 {
    let i = x as i32;
    if (i as f32) > x {
        i.saturating_sub(1)
    } else {
        i
    }
}

/// The cells of the box from `lo` to `hi`, both included, z slowest: the grid walks of the
/// binned searches (signed distances, following's crossing test, the level set's scan).
pub(crate) fn cells_between(lo: glam::IVec3, hi: glam::IVec3) -> impl Iterator<Item = glam::IVec3> {
    (lo.z..=hi.z).flat_map(move |z| {
        (lo.y..=hi.y).flat_map(move |y| (lo.x..=hi.x).map(move |x| glam::IVec3::new(x, y, z)))
    })
}

#[cfg(test)]
mod tests {
    use super::floor_i32;

    /// The libm-free floor is libm's, saturating as `as` does, at the edges that matter.
    #[test]
    fn floor_is_libms() {
        for x in [
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            2.9999998,
            -2.9999998,
            1e-30,
            -1e-30,
            16777217.0,
            -16777217.0,
            2147483520.0,
            -2147483648.0,
            3e9,
            -3e9,
            f32::MAX,
            f32::MIN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ] {
            assert_eq!(floor_i32(x), x.floor() as i32, "{x}");
        }
    }
}
