//! Approach (2) of Rosenberg & Birdwell 2008, Fig. 7: surface-following Marching Cubes in the
//! blocks of Sec. 3, each block's corners in 3D arrays over all its N_z + 1 slices (Sec. 4's
//! "equivalent surface-following marching cubes") and its particles in a coarse voxel grid
//! with a 3×3×3 lookup.

use glam::{DVec3, IVec3, Vec3};

use super::Figures;
use super::follow::{Bounds, Corners, Follower};
use super::particle_grid::{ArrayCells, ParticleGrid};
use super::sampler::Sampler;
use crate::error::Result;
use crate::field::ScalarField;
use crate::neighbours::neighbourhood::reach;
use crate::recon::engines::marching_slices::blocks::Block;
use crate::recon::engines::marching_slices::marching::BlockMesh;
use crate::recon::engines::marching_slices::marching::Setting;
use crate::recon::engines::marching_slices::missed_seeds::MissedSeeds;
use crate::recon::engines::marching_slices::seeds::particle_seeds;

/// A block's corners, x fastest: values, whether computed, the vertices on their three edges
/// (1 + the vertex, 0 for none), gradients (with `normals = "grid"`), and a bit per cube done.
struct ArrayCorners<'a, F: ScalarField + ?Sized> {
    sampler: Sampler<'a, ArrayCells, F>,
    n: usize,
    values: Vec<f32>,
    known: Vec<u64>,
    vertices: Vec<[u32; 3]>,
    gradients: Vec<Vec3>,
    done: Vec<u64>,
}

impl<F: ScalarField + ?Sized> ArrayCorners<'_, F> {
    fn corner(&self, c: IVec3) -> usize {
        let side = self.n + 1;
        (c.z as usize * side + c.y as usize) * side + c.x as usize
    }

    fn cube(&self, c: IVec3) -> usize {
        (c.z as usize * self.n + c.y as usize) * self.n + c.x as usize
    }
}

fn bit(bits: &[u64], i: usize) -> bool {
    bits[i >> 6] >> (i & 63) & 1 != 0
}

impl<F: ScalarField + ?Sized> Corners for ArrayCorners<'_, F> {
    fn value(&mut self, c: IVec3) -> f32 {
        let i = self.corner(c);
        if !bit(&self.known, i) {
            self.values[i] = self.sampler.value(c);
            self.known[i >> 6] |= 1 << (i & 63);
        }
        self.values[i]
    }

    fn gradient(&mut self, c: IVec3) -> Vec3 {
        let i = self.corner(c);
        if self.gradients[i].x.is_nan() {
            self.gradients[i] = self.sampler.gradient(c);
        }
        self.gradients[i]
    }

    fn vertex(&self, c: IVec3, axis: usize) -> Option<u32> {
        self.vertices[self.corner(c)][axis].checked_sub(1)
    }

    fn set_vertex(&mut self, c: IVec3, axis: usize, id: u32) {
        let i = self.corner(c);
        self.vertices[i][axis] = id + 1;
    }

    fn done(&self, cube: IVec3) -> bool {
        bit(&self.done, self.cube(cube))
    }

    fn set_done(&mut self, cube: IVec3) {
        let i = self.cube(cube);
        self.done[i >> 6] |= 1 << (i & 63);
    }

    fn heap_bytes(&self) -> usize {
        self.values.capacity() * size_of::<f32>()
            + (self.known.capacity() + self.done.capacity()) * size_of::<u64>()
            + self.vertices.capacity() * size_of::<[u32; 3]>()
            + self.gradients.capacity() * size_of::<Vec3>()
    }
}

/// The bytes of a block's corner arrays, `cubes` per side with its margins.
pub fn array_bytes(cubes: i32, corner_gradients: bool) -> u64 {
    let corners = (cubes as u64 + 1).pow(3);
    let per_corner = 4 + 12 + if corner_gradients { 12 } else { 0 };
    corners * per_corner + corners / 4
}

/// Follows the surface through one block, from the slices engine's seeds.
pub fn march<F: ScalarField + ?Sized>(
    set: &Setting<F>,
    block: &Block,
) -> Result<(BlockMesh, Figures)> {
    let n = block.size + 2 * block.margin;
    let origin = block.lo - block.margin;
    let handlers = set.handlers;
    let (positions, channels) = handlers.gather(&block.particles);
    // In cube units of the block, as the slices engine's lookup cache takes them.
    let cell = f64::from(set.cell);
    let local: Vec<DVec3> = positions
        .iter()
        .map(|p| p.as_dvec3() / cell - origin.as_dvec3())
        .collect();
    let support = set.field.support();
    let own_reach = set.field.reach_channel();
    let grid = {
        let particle_reach = reach(&channels, support, own_reach);
        let cubes = |i: usize| f64::from(particle_reach(i)) / cell;
        ParticleGrid::array(local.clone(), &cubes, own_reach.is_none())
    };
    let side = n as usize + 1;
    let corners = ArrayCorners {
        sampler: Sampler::new(
            grid,
            positions,
            channels,
            set.field,
            origin,
            set.cell,
            Some(side as i32),
        ),
        n: n as usize,
        values: vec![0.0; side.pow(3)],
        known: vec![0; side.pow(3).div_ceil(64)],
        vertices: vec![[0; 3]; side.pow(3)],
        gradients: if set.corner_gradients {
            vec![Vec3::NAN; side.pow(3)]
        } else {
            Vec::new()
        },
        done: vec![0; (n as usize).pow(3).div_ceil(64)],
    };
    let bounds = Bounds {
        n,
        margin: block.margin,
        size: block.size,
    };
    let mut f = Follower::new(
        corners,
        origin,
        set.cell,
        set.corner_gradients,
        Some(bounds),
    );
    let cache_bytes = f.corners.sampler.heap_bytes() + block.heap_bytes();
    let counted = set.in_flight.add(f.corners.heap_bytes() + cache_bytes);
    let reach_slabs = (f64::from(support) / cell).ceil() as i32;
    for cube in particle_seeds(
        local.len(),
        |i| local[i],
        reach_slabs,
        Some(n - 1),
        |c| f.corners.value(c),
    ) {
        f.push(cube);
    }
    drop(local);
    f.run();
    // The slices engine's second pass, from the same crossings.
    let seeds = MissedSeeds {
        handlers,
        field: set.field,
        spacing: set.spacing,
        cell: set.cell,
        lo: block.lo,
        size: block.size,
    };
    for (c, axis) in seeds.crossing_edges(&f.corners.sampler.positions)? {
        let (a, b) = (IVec3::AXES[(axis + 1) % 3], IVec3::AXES[(axis + 2) % 3]);
        let edge = c - origin;
        for cube in [edge, edge - a, edge - b, edge - a - b] {
            if f.within(cube) && !f.corners.done(cube) {
                f.push(cube);
            }
        }
    }
    f.run();
    set.in_flight.sub(counted);
    let figures = Figures {
        cubes_visited: f.cubes_visited,
        corners: f.corners.sampler.corners,
        render_bytes: f.corners.heap_bytes() + f.todo_bytes,
        cache_bytes,
    };
    Ok((f.mesh, figures))
}
