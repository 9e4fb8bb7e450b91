//! The scalar fields against brute force: every kind, the anisotropic kernels, gradients and
//! the band's sampling.

mod anisotropic;
mod field_kinds;
mod field_sampling;
mod gradients;
