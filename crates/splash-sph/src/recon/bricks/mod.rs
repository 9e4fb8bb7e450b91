//! The narrow band stored as bricks of 8³ vertices (Sec. 4.1's band, with the coarse-cell
//! indexing of Wu et al. 2016): the band's bits, its values and signs, the bricks' neighbours
//! and halos, and the per-brick Marching Cubes tests (surface cells, edge tables).

pub(crate) mod band;
pub(crate) mod brick_neighbours;
pub(crate) mod brick_signs;
pub(crate) mod brick_values;
pub(crate) mod edge_tables;
pub(crate) mod halo;
pub(crate) mod surface_cells;
