//! Scalar fields whose zero level set is the fluid surface. Every engine samples a field through
//! this trait and the Marching Cubes code never asks which one it is.

pub mod ssp07;

use glam::Vec3;

use crate::recon::neighbourhood::Neighbourhood;

pub trait ScalarField: Sync {
    /// Particles farther than this from a point do not change the field there.
    fn support(&self) -> f32;

    /// The field at `x` (relative to `near.anchor`, as the particles of `near` are): negative
    /// inside the fluid, zero on its surface. `near` holds every particle within
    /// [`support`](Self::support) of `x`, and may hold others.
    fn value(&self, near: &Neighbourhood, x: Vec3) -> f32;
}
