//! Surface reconstruction engines.

pub mod band;
pub mod band_closure;
pub mod field_sampling;
pub mod full_grid;
pub mod halo;
pub mod handler_array;
pub mod marching_slices;
pub mod narrow_band;
pub mod neighbourhood;
pub mod normals;
pub mod scatter;
pub mod surface_particles;
pub mod triangulation;

pub use narrow_band::{Engine, Limits, Reconstruction, reconstruct, reconstruct_with};
