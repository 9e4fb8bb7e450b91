//! The library's tests that reach inside it: fields against brute force, the band and the
//! triangulation, engines against each other, on analytic shapes and real frames.

mod anisotropic;
pub(crate) mod common;
mod correction;
mod engines;
mod field_kinds;
mod field_sampling;
mod gradients;
mod iso;
mod iso_components;
mod lambda2;
mod marching_cubes;
mod post;
#[cfg(target_os = "linux")]
mod post_stages;
mod reconstruction;
mod slices;
mod surface_following;
mod temporal;

/// The helpers the integration tests and the command line's tests share.
#[allow(dead_code)]
#[path = "../../tests/common/support.rs"]
mod support;
