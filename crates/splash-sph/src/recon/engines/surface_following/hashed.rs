//! Approach (3) of Rosenberg & Birdwell 2008, Fig. 7: surface-following Marching Cubes,
//! unbounded, with the corners in a hash map and the particles in a hashed voxel grid with a
//! 3×3×3 lookup (the paper's "hash map based approaches" for unbounded rendering).

use std::collections::hash_map::Entry as Slot;

use glam::{DVec3, IVec3, Vec3};
use rustc_hash::FxHashMap;

use super::Figures;
use super::follow::{Corners, Follower};
use super::hash_bytes;
use super::particle_grid::{HashedCells, ParticleGrid};
use super::sampler::Sampler;
use crate::error::Result;
use crate::field::ScalarField;
use crate::neighbours::neighbourhood::reach;
use crate::recon::engines::marching_slices::blocks::Block;
use crate::recon::engines::marching_slices::marching::BlockMesh;
use crate::recon::engines::marching_slices::marching::Setting;
use crate::recon::engines::marching_slices::missed_seeds::MissedSeeds;
use crate::recon::engines::marching_slices::seeds::particle_seeds;

/// A computed corner: its value, the vertices on its three edges (1 + the vertex, 0 for
/// none), and whether the cube it is the lowest corner of was visited.
#[derive(Clone, Copy)]
struct Corner {
    value: f32,
    vertices: [u32; 3],
    done: bool,
}

struct HashedCorners<'a, F: ScalarField + ?Sized> {
    sampler: Sampler<'a, HashedCells, F>,
    map: FxHashMap<IVec3, Corner>,
    gradients: FxHashMap<IVec3, Vec3>,
}

impl<F: ScalarField + ?Sized> Corners for HashedCorners<'_, F> {
    fn value(&mut self, c: IVec3) -> f32 {
        match self.map.entry(c) {
            Slot::Occupied(e) => e.get().value,
            Slot::Vacant(e) => {
                let value = self.sampler.value(c);
                e.insert(Corner {
                    value,
                    vertices: [0; 3],
                    done: false,
                });
                value
            }
        }
    }

    fn gradient(&mut self, c: IVec3) -> Vec3 {
        match self.gradients.entry(c) {
            Slot::Occupied(e) => *e.get(),
            Slot::Vacant(e) => *e.insert(self.sampler.gradient(c)),
        }
    }

    fn vertex(&self, c: IVec3, axis: usize) -> Option<u32> {
        self.map[&c].vertices[axis].checked_sub(1)
    }

    fn set_vertex(&mut self, c: IVec3, axis: usize, id: u32) {
        self.map.get_mut(&c).expect("a computed corner").vertices[axis] = id + 1;
    }

    fn done(&self, cube: IVec3) -> bool {
        self.map.get(&cube).is_some_and(|c| c.done)
    }

    fn set_done(&mut self, cube: IVec3) {
        self.map.get_mut(&cube).expect("a computed corner").done = true;
    }

    fn heap_bytes(&self) -> usize {
        hash_bytes(&self.map) + hash_bytes(&self.gradients)
    }
}

/// Follows the surface of all particles in one pass, from the slices engine's seeds: those
/// of each particle, then those around the crossings near sparse particles that the walk
/// missed, looked for block by block (`tiles`: the slices engine's blocks, for their particle
/// lists only).
pub fn march<F: ScalarField + ?Sized>(
    set: &Setting<F>,
    tiles: &[Block],
) -> Result<(BlockMesh, Figures)> {
    let handlers = set.handlers;
    // The particles by height, as the slices engine numbers each block's.
    let mut order: Vec<u32> = (0..handlers.positions.len() as u32).collect();
    let z = |i: &u32| handlers.positions[*i as usize].z;
    order.sort_unstable_by(|a, b| z(a).total_cmp(&z(b)).then(a.cmp(b)));
    let (positions, channels) = handlers.gather(&order);
    drop(order);
    let cell = f64::from(set.cell);
    let global: Vec<DVec3> = positions.iter().map(|p| p.as_dvec3() / cell).collect();
    let support = set.field.support();
    let own_reach = set.field.reach_channel();
    let grid = {
        let particle_reach = reach(&channels, support, own_reach);
        let cubes = |i: usize| f64::from(particle_reach(i)) / cell;
        ParticleGrid::hashed(global.clone(), &cubes, own_reach.is_none())
    };
    let corners = HashedCorners {
        sampler: Sampler::new(
            grid,
            positions,
            channels,
            set.field,
            IVec3::ZERO,
            set.cell,
            None,
        ),
        map: FxHashMap::default(),
        gradients: FxHashMap::default(),
    };
    let mut f = Follower::new(corners, IVec3::ZERO, set.cell, set.corner_gradients, None);
    let reach_slabs = (f64::from(support) / cell).ceil() as i32;
    for cube in particle_seeds(
        global.len(),
        |i| global[i],
        reach_slabs,
        None,
        |c| f.corners.value(c),
    ) {
        f.push(cube);
    }
    drop(global);
    f.run();
    for tile in tiles {
        let seeds = MissedSeeds {
            handlers,
            field: set.field,
            spacing: set.spacing,
            cell: set.cell,
            lo: tile.lo,
            size: tile.size,
        };
        let positions: Vec<Vec3> = tile
            .particles
            .iter()
            .map(|&h| handlers.positions[h as usize])
            .collect();
        for (c, axis) in seeds.crossing_edges(&positions)? {
            let (a, b) = (IVec3::AXES[(axis + 1) % 3], IVec3::AXES[(axis + 2) % 3]);
            for cube in [c, c - a, c - b, c - a - b] {
                if !f.corners.done(cube) {
                    f.push(cube);
                }
            }
        }
        f.run();
    }
    let figures = Figures {
        cubes_visited: f.cubes_visited,
        corners: f.corners.sampler.corners,
        render_bytes: f.corners.heap_bytes() + f.todo_bytes,
        cache_bytes: f.corners.sampler.heap_bytes(),
    };
    Ok((f.mesh, figures))
}
