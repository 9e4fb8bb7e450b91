//! The library's tests that reach inside it: fields against brute force, the band and the
//! triangulation, engines against each other, on analytic shapes and real frames.

pub(crate) mod common;
mod engines;
mod field;
mod iso;
pub(crate) mod post;

/// The helpers the integration tests and the command line's tests share.
#[allow(dead_code)]
#[path = "../../tests/common/support.rs"]
mod support;
