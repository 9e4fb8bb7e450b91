//! The one internal trait every engine samples a field through (value and analytic gradient at
//! a point from a gathered neighbourhood), and the optional forms some fields add: signs from
//! bounds, per-vertex sums for the scatter engine, and kernels fitted to a frame.

use glam::Vec3;

use super::radial_kernel::RadialKernel;
use crate::error::Result;
use crate::neighbours::handler_array::HandlerArray;
use crate::neighbours::neighbourhood::Neighbourhood;

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

    /// For fields whose only channel is the density field's particle volume: the support of
    /// its summation, so that a pass over the same neighbourhoods can compute it alongside
    /// ([`particle_volume`](super::density::particle_volume)). `None` for the others.
    fn volume_support(&self) -> Option<f32> {
        None
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

    /// Whether the field's value is a distance (SSP07's and ZB05's, in world units): how far a
    /// vertex lies from the surface then shows in its value.
    fn is_distance(&self) -> bool {
        false
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
