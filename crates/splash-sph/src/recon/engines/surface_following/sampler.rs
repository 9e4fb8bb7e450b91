//! The field at a grid corner for the surface-following baselines (Rosenberg & Birdwell 2008,
//! Sec. 7): the particles within reach from the point-insert 3D-lookup cache, summed as the
//! slices engine sums them, so that every approach computes the same value to the bit.

use glam::{IVec3, Vec3};

use super::particle_grid::{Cells, ParticleGrid};
use crate::field::ScalarField;
use crate::neighbours::neighbourhood::Neighbourhood;
use crate::recon::stages::field_sampling::vertex_position;

pub struct Sampler<'a, C, F: ScalarField + ?Sized> {
    pub grid: ParticleGrid<C>,
    /// The particles by height, as the grid numbers them, and their channels.
    pub positions: Vec<Vec3>,
    pub channels: Vec<Vec<f32>>,
    pub field: &'a F,
    /// Global index of corner (0, 0, 0).
    pub origin: IVec3,
    pub cell: f32,
    /// Corners per side of a block, whose boundary corners reach no particle (the field is
    /// forced outside there, Sec. 3); unbounded without.
    pub side: Option<i32>,
    near: Neighbourhood,
    found: Vec<u32>,
    /// Corners sampled.
    pub corners: usize,
}

impl<'a, C: Cells, F: ScalarField + ?Sized> Sampler<'a, C, F> {
    pub fn new(
        grid: ParticleGrid<C>,
        positions: Vec<Vec3>,
        channels: Vec<Vec<f32>>,
        field: &'a F,
        origin: IVec3,
        cell: f32,
        side: Option<i32>,
    ) -> Self {
        Sampler {
            grid,
            positions,
            channels,
            field,
            origin,
            cell,
            side,
            near: Neighbourhood::default(),
            found: Vec::new(),
            corners: 0,
        }
    }

    pub fn value(&mut self, c: IVec3) -> f32 {
        self.gather(c);
        self.corners += 1;
        self.field.value(&self.near, Vec3::ZERO)
    }

    pub fn gradient(&mut self, c: IVec3) -> Vec3 {
        self.gather(c);
        self.field.gradient(&self.near, Vec3::ZERO)
    }

    fn gather(&mut self, c: IVec3) {
        self.found.clear();
        let boundary = self
            .side
            .is_some_and(|s| c.min_element() <= 0 || c.max_element() >= s - 1);
        if !boundary {
            self.grid.within_reach(c, &mut self.found);
        }
        let anchor = vertex_position(self.origin + c, self.cell);
        let candidates = self.found.iter().map(|&i| (i as usize, true));
        self.near
            .pick(anchor, candidates, &self.positions, &self.channels);
    }

    /// Bytes held: the grid and the particles' copies (the paper's "cache memory").
    pub fn heap_bytes(&self) -> usize {
        self.grid.heap_bytes()
            + self.positions.capacity() * size_of::<Vec3>()
            + self
                .channels
                .iter()
                .map(|c| c.capacity() * size_of::<f32>())
                .sum::<usize>()
    }
}
