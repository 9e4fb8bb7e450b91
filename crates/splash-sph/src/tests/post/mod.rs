//! Post-processing and sequences: analytic shapes, each stage's figures and surfaces that
//! follow the fluid.

#[cfg(target_os = "linux")]
mod post_stages;
pub(crate) mod shapes;
mod temporal;
