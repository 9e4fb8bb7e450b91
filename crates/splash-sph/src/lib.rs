//! splash: closed triangle meshes from SPH particle frames.
//!
//! The parallel narrow-band reconstruction of Akinci et al. 2012 with six scalar fields
//! (SSP07 by default), four engines, particle readers and mesh writers. The full gather, the
//! scatter and Marching Slices give the same surface; the narrow band (the default) samples only
//! a band around the surface particles and misses the blobs of a cell or two that small cells
//! show beyond it (1 of 55 components, 8 triangles, on cbd-small frame 40 at cell r/2), and
//! gives the full gather's mesh elsewhere.
//!
//! ```
//! use splash_sph::{Config, Reconstructor, Vec3};
//!
//! // A ball of particles on a lattice of spacing r = 0.1.
//! let r = 0.1;
//! let mut positions = Vec::new();
//! for (x, y, z) in (-5..=5).flat_map(|x| (-5..=5).flat_map(move |y| (-5..=5).map(move |z| (x, y, z)))) {
//!     let p = Vec3::new(x as f32, y as f32, z as f32) * r;
//!     if p.length() <= 0.5 {
//!         positions.push(p);
//!     }
//! }
//! let config = Config { spacing: Some(r), ..Config::default() };
//! let result = Reconstructor::new(config)?.reconstruct(&positions)?;
//! assert!(result.mesh.triangles.len() > 100);
//! assert_eq!(result.stats.particles, positions.len());
//! # Ok::<(), splash_sph::Error>(())
//! ```

#![deny(missing_docs)]

#[macro_use]
mod error;

pub mod attribute_names;
mod attributes;
mod config;
mod data;
mod length;
mod neighbours;
mod overrides;
mod reconstructor;
mod spacing;
mod worker_pool;

pub mod bytes;
pub mod field;
pub mod frames;
pub mod io;
pub mod iso;
pub mod level_set;
pub mod mesh;
pub mod pipeline;
pub mod preview;
mod recon;
pub mod report;
pub mod temporal;

pub use bytes::Bytes;
pub use config::{
    BandConfig, Baseline, Config, Engine, Normals, OutputConfig, SlicesConfig, SurfaceParticles,
};
pub use data::{Attribute, MeshFormat, Particles, TriMesh, UpAxis};
pub use error::{Error, Result};
pub use glam::Vec3;
pub use io::{InputFormat, read_particles};
pub use length::Length;
pub use overrides::{OPTIONS, OptionSpec, OptionValue, Overrides, Spelling, option};
pub use recon::Reconstruction;
pub use reconstructor::Reconstructor;
pub use report::{Clock, CorrectionFigures, FrameStats, Observer, Stage, StageFigures};
pub use spacing::estimate_spacing;
pub use worker_pool::install;

#[cfg(test)]
mod tests;
