//! Surface following (Sec. III-D1): a queue of cells started from the seeds, each classified by
//! Marching Cubes on the interpolant at its corners, its neighbours across crossed faces queued
//! unless visited. Cells are taken in lexicographic (z, y, x) order, a z slice at a time, so the
//! slice cache keeps the nodes they share; a slice's missing nodes are evaluated in parallel.
//! Which cells are visited does not depend on the order, nor on the threads.

use std::collections::BTreeSet;

use glam::IVec3;
use rayon::prelude::*;
use rustc_hash::FxHashSet;

use super::slice_cache::{Node, SliceCache};
use super::sph_interpolant::Interpolant;
use super::virtual_grid::VirtualGrid;
use crate::error::Result;
use crate::mesh::marching_cubes::corner_offset;

/// A cell the isosurface crosses, with A − level at its corners.
#[derive(Debug, Clone, Copy)]
pub(crate) struct CrossedCell {
    pub cell: IVec3,
    pub values: [f64; 8],
}

impl CrossedCell {
    /// Marching Cubes case: bit c set when corner c is below the level.
    pub fn case(&self) -> usize {
        case_of(&self.values)
    }
}

pub(crate) fn case_of(values: &[f64; 8]) -> usize {
    (0..8).fold(0, |acc, c| acc | (usize::from(values[c] < 0.0) << c))
}

/// What the queue found.
pub(crate) struct Followed {
    /// Crossed cells, in lexicographic order.
    pub cells: Vec<CrossedCell>,
    /// Cells materialised: seeds and cells reached from them.
    pub visited: usize,
    /// Cells dropped for a corner below the node threshold.
    pub discarded: usize,
    pub cache: SliceCache,
}

/// The tuning of one run.
pub(crate) struct Following {
    pub level: f64,
    pub node_threshold: f64,
    pub cache_slices: u32,
    pub max_cells: u64,
}

fn key(c: IVec3) -> [i32; 3] {
    [c.z, c.y, c.x]
}

fn corner(cell: IVec3, c: usize) -> IVec3 {
    let [x, y, z] = corner_offset(c);
    cell + IVec3::new(x as i32, y as i32, z as i32)
}

/// Follows the isosurface from `seeds` over the virtual grid.
pub(crate) fn follow(
    it: &Interpolant,
    grid: &VirtualGrid,
    seeds: &[IVec3],
    run: &Following,
) -> Result<Followed> {
    let too_many = |n: usize| -> Result<()> {
        if n as u64 > run.max_cells {
            bail_limit!(
                "the isosurface needs more than {} virtual cells (iso.max_cells); use a larger \
                 --cell",
                run.max_cells
            );
        }
        Ok(())
    };
    too_many(seeds.len())?;
    let mut pending: BTreeSet<[i32; 3]> = seeds.iter().map(|&c| key(c)).collect();
    let mut visited: FxHashSet<IVec3> = FxHashSet::default();
    let mut cache = SliceCache::new(run.cache_slices);
    let (mut cells, mut discarded) = (Vec::new(), 0);
    let (mut batch, mut missing) = (Vec::new(), Vec::new());
    while let Some(&[z0, ..]) = pending.first() {
        batch.clear();
        while let Some(k) = pending.first().filter(|k| k[0] == z0).copied() {
            pending.pop_first();
            let cell = IVec3::new(k[2], k[1], k[0]);
            if visited.insert(cell) {
                batch.push(cell);
            }
        }
        too_many(visited.len())?;
        cache.retain_up_to(z0 + 1);
        missing.clear();
        for &cell in &batch {
            missing.extend(
                (0..8)
                    .map(|c| corner(cell, c))
                    .filter(|&n| cache.get(n).is_none()),
            );
        }
        missing.sort_unstable_by_key(|&n| key(n));
        missing.dedup();
        let nodes: Vec<Node> = missing
            .par_iter()
            .map(|&n| {
                let s = it.sample(grid.node(n), it.channels.value);
                Node {
                    value: s.value,
                    weight: s.weight,
                }
            })
            .collect();
        for (&n, &node) in missing.iter().zip(&nodes) {
            cache.insert(n, node);
        }
        cache.count(8 * batch.len(), missing.len());
        for &cell in &batch {
            let nodes: [Node; 8] = std::array::from_fn(|c| {
                cache
                    .get(corner(cell, c))
                    .expect("the batch's nodes were just cached")
            });
            if nodes.iter().any(|n| n.weight < run.node_threshold) {
                discarded += 1;
                continue;
            }
            let values = nodes.map(|n| n.value - run.level);
            let case = case_of(&values);
            if case == 0 || case == 255 {
                continue;
            }
            cells.push(CrossedCell { cell, values });
            for axis in 0..3 {
                for side in 0..2 {
                    let face = (0..8).filter(|c| (c >> axis) & 1 == side);
                    let below = face.map(|c| (case >> c) & 1).sum::<usize>();
                    if below == 0 || below == 4 {
                        continue;
                    }
                    let mut next = cell;
                    next[axis] += if side == 1 { 1 } else { -1 };
                    if !visited.contains(&next) {
                        pending.insert(key(next));
                    }
                }
            }
        }
    }
    cells.sort_unstable_by_key(|c| key(c.cell));
    Ok(Followed {
        cells,
        visited: visited.len(),
        discarded,
        cache,
    })
}
