//! Spatial grids and neighbour searches, below the fields and the engines that gather with
//! them: the handler array of Akinci et al. 2012 (Sec. 4.1, eq. 8) and the neighbourhoods
//! gathered from it, narrowed per brick, block and vertex.

pub(crate) mod box_filter;
pub(crate) mod bucket_grid;
mod cell_keys;
mod counting_sort;
pub(crate) mod handler_array;
pub(crate) mod lane;
pub(crate) mod lane_sums;
pub(crate) mod neighbourhood;

pub(crate) use cell_keys::CellKeys;
pub(crate) use handler_array::{ceil_i32, cell_of, floor_i32};
