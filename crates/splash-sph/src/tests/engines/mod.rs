//! The engines and the triangulation: agreement between engines, Marching Cubes, whole
//! reconstructions, Marching Slices, surface following, the vertex correction and the field
//! averaged along the flow.

mod agreement;
mod correction;
mod flow_mean;
mod marching_cubes;
mod reconstruction;
mod slices;
mod surface_following;
