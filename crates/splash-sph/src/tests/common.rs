//! The helpers of every test (shared with the command line's tests), and parameters and
//! reconstructions reached from inside the library.

use glam::Vec3;

pub use super::shared::*;
use crate::config::{Config, Params};
use crate::field::FieldConfig;
use crate::length::Length;

/// The default parameters (SSP07) at spacing `r` and cell size `cell`.
pub fn params(r: f32, cell: &str) -> Params {
    field_params("ssp07", r, cell)
}

/// The defaults of the field `kind` at spacing `r` and cell size `cell`.
pub fn field_params(kind: &str, r: f32, cell: &str) -> Params {
    let config = Config {
        cell: Length::parse(cell).unwrap(),
        field: FieldConfig::named(kind).unwrap(),
        ..Config::default()
    };
    Params::resolve(&config, r)
}

/// Reconstructs `particles` with `params` and `engine`, as the engines' dispatch does.
pub fn reconstruct(
    particles: &[Vec3],
    params: &Params,
    engine: crate::Engine,
) -> crate::Result<crate::Reconstruction> {
    let params = Params {
        engine,
        ..params.clone()
    };
    crate::recon::reconstruct(particles, &params, None)
}
