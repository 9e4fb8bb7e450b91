//! The engines and the triangulation: agreement between engines, Marching Cubes, whole
//! reconstructions, Marching Slices, surface following and the vertex correction.

mod agreement;
mod correction;
mod marching_cubes;
mod reconstruction;
mod slices;
mod surface_following;
