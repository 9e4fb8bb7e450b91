//! The four engines, each running the stages its own way: the narrow band (Algorithm 1 of
//! Akinci et al. 2012), the full gather and the scatter over the full grid, and block-parallel
//! Marching Slices (Rosenberg & Birdwell 2008); and the baselines that paper measures Marching
//! Slices against, for `splash bench slices` (`surface_following/`).
//!
//! The full gather, the scatter and Marching Slices give the same surface, component for
//! component (the scatter and slices sum in another order: vertices may differ in the last
//! bits). The narrow band misses the blobs of a cell or two that small cells show beyond its
//! band (1 of 55 components, 8 triangles, on cbd-small frame 40 at cell r/2; the slices engine
//! finds them by its missed seeds), and elsewhere gives the full gather's mesh bit for bit.

pub(crate) mod full_grid;
pub(crate) mod marching_slices;
pub(crate) mod narrow_band;
pub(crate) mod prepared;
pub(crate) mod scatter;
pub(crate) mod surface_following;
