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

/// A point of the unit cube from three numbers of `next` (x, y, z in that order).
pub fn uniform_point(next: &mut impl FnMut() -> f32) -> Vec3 {
    Vec3::new(next(), next(), next())
}

/// A fixed stream of pseudo-random numbers in [0, 1) from `seed` (an LCG: the tests need
/// repeatable scatter, not quality).
pub fn uniform(seed: u64) -> impl FnMut() -> f32 {
    let mut state = seed;
    move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 40) as f32 / (1u64 << 24) as f32
    }
}
