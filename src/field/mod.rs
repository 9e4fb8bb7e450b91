//! Scalar fields whose zero level set is the fluid surface. Every engine samples a field through
//! [`ScalarField`], and the Marching Cubes code never asks which one it is.

pub mod blobby;
pub mod density;
pub mod metaball;
pub mod ssp07;
pub mod zb05;

use anyhow::{Result, bail};
use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::recon::neighbourhood::Neighbourhood;

pub trait ScalarField: Sync {
    /// Particles farther than this from a point do not change the field there.
    fn support(&self) -> f32;

    /// The field at `x` (relative to `near.anchor`, as the particles of `near` are): negative
    /// inside the fluid, zero on its surface. `near` holds every particle within
    /// [`support`](Self::support) of `x`, and may hold others.
    fn value(&self, near: &Neighbourhood, x: Vec3) -> f32;

    /// For fields that weight each particle by its volume m/ρ: the support of the SPH kernel
    /// that gives the particles' densities. The engines then put them in channel 0 of
    /// `Neighbourhood::channels`.
    fn particle_volume_support(&self) -> Option<f32> {
        None
    }
}

/// The `[field]` table of a configuration: `kind` picks the field, the other keys are its own.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum FieldConfig {
    Ssp07(ssp07::Ssp07Config),
    Zb05(zb05::Zb05Config),
    Density(density::DensityConfig),
    Blobby(blobby::BlobbyConfig),
    Metaball(metaball::MetaballConfig),
}

impl Default for FieldConfig {
    fn default() -> Self {
        FieldConfig::Ssp07(Default::default())
    }
}

impl FieldConfig {
    pub const KINDS: [&str; 5] = ["ssp07", "zb05", "density", "blobby", "metaball"];

    /// A field of the named kind with its defaults (`--field NAME`).
    pub fn named(kind: &str) -> Result<FieldConfig> {
        Ok(match kind {
            "ssp07" => FieldConfig::Ssp07(Default::default()),
            "zb05" => FieldConfig::Zb05(Default::default()),
            "density" => FieldConfig::Density(Default::default()),
            "blobby" => FieldConfig::Blobby(Default::default()),
            "metaball" => FieldConfig::Metaball(Default::default()),
            _ => bail!(
                "unknown field '{kind}': use one of {}",
                Self::KINDS.join(", ")
            ),
        })
    }

    pub fn kind(&self) -> &'static str {
        match self {
            FieldConfig::Ssp07(_) => "ssp07",
            FieldConfig::Zb05(_) => "zb05",
            FieldConfig::Density(_) => "density",
            FieldConfig::Blobby(_) => "blobby",
            FieldConfig::Metaball(_) => "metaball",
        }
    }

    pub fn validate(&self) -> Result<()> {
        match self {
            FieldConfig::Ssp07(c) => c.validate(),
            FieldConfig::Zb05(c) => c.validate(),
            FieldConfig::Density(c) => c.validate(),
            FieldConfig::Blobby(c) => c.validate(),
            FieldConfig::Metaball(c) => c.validate(),
        }
    }

    /// The field in world units for particle spacing `r`.
    pub fn build(&self, r: f32) -> Box<dyn ScalarField> {
        match self {
            FieldConfig::Ssp07(c) => Box::new(c.resolve(r)),
            FieldConfig::Zb05(c) => Box::new(c.resolve(r)),
            FieldConfig::Density(c) => Box::new(c.resolve(r)),
            FieldConfig::Blobby(c) => Box::new(c.resolve(r)),
            FieldConfig::Metaball(c) => Box::new(c.resolve(r)),
        }
    }
}
