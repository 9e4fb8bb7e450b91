//! The four engines, each running the stages its own way to the same mesh: the narrow band
//! (Algorithm 1 of Akinci et al. 2012), the full gather and the scatter over the full grid, and
//! block-parallel Marching Slices (Rosenberg & Birdwell 2008); and the baselines that paper
//! measures Marching Slices against, for `splash bench slices` (`surface_following/`).

pub(crate) mod full_grid;
pub(crate) mod marching_slices;
pub(crate) mod narrow_band;
pub(crate) mod prepared;
pub(crate) mod scatter;
pub(crate) mod surface_following;
