//! splash: triangle meshes from SPH particle frames, after Akinci et al. 2012.

pub mod config;
pub mod field;
pub mod mesh;
pub mod recon;
pub mod report;
