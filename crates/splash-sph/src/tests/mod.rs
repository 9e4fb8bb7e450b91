//! The library's tests that reach inside it: fields against brute force, the band and the
//! triangulation, engines against each other, on analytic shapes and real frames.

mod anisotropic;
pub(crate) mod common;
mod correction;
mod engines;
mod field;
mod fields;
mod gradients;
mod iso;
mod iso_components;
mod marching_cubes;
mod post;
mod reconstruction;
mod slices;

/// The helpers of the repository's tests/, which name this crate `splash_sph`.
#[path = "../../../../tests/common/mod.rs"]
mod shared;
