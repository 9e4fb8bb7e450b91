//! Scalar fields whose zero level set is the fluid surface, chosen and tuned by [`FieldConfig`]
//! (the `[field]` table of a configuration). Every engine samples a field through one internal
//! trait, and the Marching Cubes code never asks which one it is.

pub(crate) mod anisotropic;
pub(crate) mod blobby;
mod cubic_spline;
pub(crate) mod density;
pub(crate) mod metaball;
pub(crate) mod radial_kernel;
pub(crate) mod ssp07;
pub(crate) mod zb05;

pub use anisotropic::AnisotropicConfig;
pub use blobby::BlobbyConfig;
pub use density::DensityConfig;
pub use metaball::MetaballConfig;
pub use ssp07::Ssp07Config;
pub use zb05::Zb05Config;

use crate::error::Result;
use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::neighbours::handler_array::HandlerArray;
use crate::neighbours::neighbourhood::Neighbourhood;
use radial_kernel::RadialKernel;

pub(crate) trait ScalarField: Send + Sync {
    /// Particles farther than this from a point do not change the field there.
    fn support(&self) -> f32;

    /// The field's kernel as a weight of distance, for interpolating particle attributes.
    fn radial_kernel(&self) -> RadialKernel;

    /// The field at `x` (relative to `near.anchor`, as the particles of `near` are): negative
    /// inside the fluid, zero on its surface. `near` holds every particle within
    /// [`support`](Self::support) of `x`, and may hold others.
    fn value(&self, near: &Neighbourhood, x: Vec3) -> f32;

    /// ∇ of [`value`](Self::value) at `x`, from the same particles: it points out of the
    /// fluid, and normalised it gives the mesh's vertex normals.
    fn gradient(&self, near: &Neighbourhood, x: Vec3) -> Vec3;

    /// Per-particle values the field needs beside the positions (the density field: each
    /// particle's volume m/ρ), computed once per frame in `handlers`' order. The engines store
    /// them as the handler array's channels, gathered into `Neighbourhood::channels`.
    fn particle_channels(&self, _handlers: &HandlerArray) -> Vec<Vec<f32>> {
        Vec::new()
    }

    /// For fields whose kernels adapt to the particles around them (the anisotropic field):
    /// the field fitted to the frame in `handlers`, to be sampled instead of `self` and
    /// gathered from the handler array it comes with. `None` for the others.
    fn fit(&self, _handlers: &HandlerArray) -> Option<Result<Fitted>> {
        None
    }

    /// For fields whose particles reach different distances: the channel that holds each
    /// particle's own reach (at most [`support`](Self::support)). The sampling then narrows
    /// each vertex's list to the particles that reach it.
    fn reach_channel(&self) -> Option<usize> {
        None
    }

    /// For fields whose value follows from per-vertex sums that each particle adds to on its
    /// own: that form, for the scatter engine. `None` for the others.
    fn scattering(&self) -> Option<&dyn Scattering> {
        None
    }

    /// For fields whose sign often costs far less than their value (SSP07: bounds on its
    /// eigenvalue settle the sign without it): that form, so that the sampling can leave out
    /// the values no triangle reads. `None` for the others.
    fn sign_first(&self) -> Option<&dyn SignFirst> {
        None
    }
}

/// What [`SignFirst::value_or_sign`] found at a point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Sampled {
    /// The field's value, as [`ScalarField::value`] gives it, to the bit.
    Value(f32),
    /// The field is below −margin (inside) or above margin (outside) there.
    Beyond { inside: bool },
}

/// A field whose sign at a point can be settled from cheap bounds, where the point lies far
/// enough from the surface.
pub(crate) trait SignFirst: Sync {
    /// The value at `x` (as [`ScalarField::value`] takes it), unless bounds show that the
    /// field lies more than `margin` from zero there; then only which side it lies on.
    fn value_or_sign(&self, near: &Neighbourhood, x: Vec3, margin: f32) -> Sampled;
}

/// A field as per-vertex kernel sums that particles add to one at a time (SSP07's sums of
/// eqs. 4–5), then turned into the field's value: the form the scatter engine needs.
pub(crate) trait Scattering: Sync {
    /// `f32` sums per grid vertex.
    fn sums_per_vertex(&self) -> usize;

    /// Adds the particle at `p` to the vertices (`xs[i]`, `y`, `z`) of one grid row; `sums`
    /// holds theirs, [`sums_per_vertex`](Self::sums_per_vertex) each, in the order of `xs`.
    fn add_to_row(&self, sums: &mut [f32], p: Vec3, xs: &[f32], y: f32, z: f32);

    /// The field at a vertex from its sums.
    fn value_of_sums(&self, sums: &[f32]) -> f32;
}

/// A field fitted to one frame, with the particles its kernels sit on: their handler array,
/// with the per-particle data the field reads in its channels.
pub(crate) struct Fitted {
    pub field: Box<dyn ScalarField>,
    pub handlers: HandlerArray,
}

/// The `[field]` table of a configuration: `kind` picks the field, the other keys are its own.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum FieldConfig {
    /// Solenthaler et al. 2007: the default.
    Ssp07(ssp07::Ssp07Config),
    /// Zhu & Bridson 2005.
    Zb05(zb05::Zb05Config),
    /// The SPH colour field (splashsurf's).
    Density(density::DensityConfig),
    /// Blinn 1982 Gaussian blobbies.
    Blobby(blobby::BlobbyConfig),
    /// Polynomial metaballs (Triquet, Gourmel).
    Metaball(metaball::MetaballConfig),
    /// Yu & Turk 2010 anisotropic kernels.
    Anisotropic(anisotropic::AnisotropicConfig),
}

impl Default for FieldConfig {
    fn default() -> Self {
        FieldConfig::Ssp07(Default::default())
    }
}

impl FieldConfig {
    /// The names of the kinds, as `kind` takes them.
    pub const KINDS: [&str; 6] = [
        "ssp07",
        "zb05",
        "density",
        "blobby",
        "metaball",
        "anisotropic",
    ];

    /// A field of the named kind with its defaults (`--field NAME`).
    pub fn named(kind: &str) -> Result<FieldConfig> {
        Ok(match kind {
            "ssp07" => FieldConfig::Ssp07(Default::default()),
            "zb05" => FieldConfig::Zb05(Default::default()),
            "density" => FieldConfig::Density(Default::default()),
            "blobby" => FieldConfig::Blobby(Default::default()),
            "metaball" => FieldConfig::Metaball(Default::default()),
            "anisotropic" => FieldConfig::Anisotropic(Default::default()),
            _ => bail_config!(
                "unknown field '{kind}': use one of {}",
                Self::KINDS.join(", ")
            ),
        })
    }

    /// The `[field]` table of kind `kind` read from `d`, without its `kind` key (None for an
    /// unknown kind). Reading the kind's struct directly keeps the positions of the keys, which
    /// the tagged enum's buffering loses: see `config::errors`.
    pub(crate) fn deserialize_kind<'de, D: serde::Deserializer<'de>>(
        kind: &str,
        d: D,
    ) -> std::result::Result<Option<FieldConfig>, D::Error> {
        Ok(Some(match kind {
            "ssp07" => FieldConfig::Ssp07(Deserialize::deserialize(d)?),
            "zb05" => FieldConfig::Zb05(Deserialize::deserialize(d)?),
            "density" => FieldConfig::Density(Deserialize::deserialize(d)?),
            "blobby" => FieldConfig::Blobby(Deserialize::deserialize(d)?),
            "metaball" => FieldConfig::Metaball(Deserialize::deserialize(d)?),
            "anisotropic" => FieldConfig::Anisotropic(Deserialize::deserialize(d)?),
            _ => return Ok(None),
        }))
    }

    /// The `kind` name of the field.
    pub fn kind(&self) -> &'static str {
        match self {
            FieldConfig::Ssp07(_) => "ssp07",
            FieldConfig::Zb05(_) => "zb05",
            FieldConfig::Density(_) => "density",
            FieldConfig::Blobby(_) => "blobby",
            FieldConfig::Metaball(_) => "metaball",
            FieldConfig::Anisotropic(_) => "anisotropic",
        }
    }

    /// Checks the ranges the TOML types cannot express, naming the key.
    pub fn validate(&self) -> Result<()> {
        match self {
            FieldConfig::Ssp07(c) => c.validate(),
            FieldConfig::Zb05(c) => c.validate(),
            FieldConfig::Density(c) => c.validate(),
            FieldConfig::Blobby(c) => c.validate(),
            FieldConfig::Metaball(c) => c.validate(),
            FieldConfig::Anisotropic(c) => c.validate(),
        }
    }

    /// The field in world units for particle spacing `r`.
    pub(crate) fn build(&self, r: f32) -> Box<dyn ScalarField> {
        match self {
            FieldConfig::Ssp07(c) => Box::new(c.resolve(r)),
            FieldConfig::Zb05(c) => Box::new(c.resolve(r)),
            FieldConfig::Density(c) => Box::new(c.resolve(r)),
            FieldConfig::Blobby(c) => Box::new(c.resolve(r)),
            FieldConfig::Metaball(c) => Box::new(c.resolve(r)),
            FieldConfig::Anisotropic(c) => Box::new(c.resolve(r)),
        }
    }
}
