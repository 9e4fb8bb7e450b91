//! splash: triangle meshes from SPH particle frames, after Akinci et al. 2012.

pub mod attributes;
pub mod batch;
pub mod bench;
pub mod config;
pub mod field;
pub mod io;
pub mod log;
pub mod memory;
pub mod mesh;
pub mod recon;
pub mod report;
pub mod sequence;
pub mod spacing;
