//! Seeds for the surfaces that walking down from each particle cannot find (Rosenberg &
//! Birdwell 2008, Sec. 4 seed only from particles; Marching Correctors, Sec. III-C: at least
//! one seed per component). At small cells the fields make blobs of one or two cells between
//! sparse particles, 0.8r to 2.6r from the nearest one (cbd-small frame 40 at cell r/2), around
//! no particle's nearest corner. After the paper's marching, the block's own corners within the
//! field's support of a sparse particle are sampled brick by brick, as the narrow band samples
//! (`field_sampling`), and every crossing edge there whose cubes were not visited seeds them.
//!
//! Only sparse particles are looked around: a corner that only bulk particles reach is inside
//! the fluid around them, and sampling the bulk would cost as much as the full grid. The cost
//! follows the surface: a shell of one support around it, at about the narrow band's cost per
//! corner, a fraction of the lookups of the marching.

use glam::{IVec3, Vec3};

use crate::error::Result;
use crate::field::ScalarField;
use crate::neighbours::handler_array::HandlerArray;
use crate::recon::bricks::band::{BRICK, Band, brick_of, local_vertex};
use crate::recon::stages::field_sampling::sample_field;

/// A particle is sparse below this fraction of the neighbours a full lattice of spacing r has
/// within the field's support: surface and splash particles are, bulk particles are not.
const SPARSE: f32 = 0.75;

/// Where the missed seeds of one block are looked for.
pub struct MissedSeeds<'a, F: ScalarField + ?Sized> {
    pub handlers: &'a HandlerArray,
    pub field: &'a F,
    /// The particle spacing r, and the cube size.
    pub spacing: f32,
    pub cell: f32,
    /// Global index of the block's first own corner, and its own cubes per side: its corners
    /// are `lo..=lo + size` on each axis.
    pub lo: IVec3,
    pub size: i32,
}

impl<F: ScalarField + ?Sized> MissedSeeds<'_, F> {
    /// The crossing edges among the block's own corners within the support of a sparse particle
    /// of `particles`, each as its lower corner (global) and axis, in (z, y, x, axis) order.
    pub fn crossing_edges(&self, particles: &[Vec3]) -> Result<Vec<(IVec3, usize)>> {
        let side = self.size + 1;
        let marked = self.sparse_neighbourhood(particles);
        let at = |c: IVec3| ((c.z * side + c.y) * side + c.x) as usize;
        let is_marked = |c: IVec3| marked[at(c) >> 6] >> (at(c) & 63) & 1 != 0;
        let plane = (side * side) as usize;
        // One layer of bricks at a time: its planes of values, after the last plane of the
        // layer below (for the edges in z between layers), NaN where not sampled.
        let mut below = vec![f32::NAN; plane];
        let mut edges = Vec::new();
        let (first, last) = (brick_of(self.lo).z, brick_of(self.lo + self.size).z);
        for bz in first..=last {
            let z0 = (bz * BRICK).max(self.lo.z) - self.lo.z;
            let z1 = (bz * BRICK + BRICK - 1).min(self.lo.z + self.size) - self.lo.z;
            let mut vertices = Vec::new();
            for z in z0..=z1 {
                for y in 0..side {
                    for x in 0..side {
                        let c = IVec3::new(x, y, z);
                        if is_marked(c) {
                            vertices.push(self.lo + c);
                        }
                    }
                }
            }
            let mut layer = vec![f32::NAN; plane * (z1 - z0 + 1) as usize];
            if !vertices.is_empty() {
                let band = Band::from_vertices(&vertices, self.cell);
                let values = sample_field(&band, self.handlers, self.field)?;
                for (b, &brick) in band.bricks.iter().enumerate() {
                    let dense = values.dense(&band.masks[b], b);
                    for (local, &v) in dense.iter().enumerate() {
                        if !v.is_nan() {
                            let c = brick * BRICK + local_vertex(local) - self.lo;
                            layer[at(c.with_z(c.z - z0))] = v;
                        }
                    }
                }
            }
            let value = |c: IVec3| {
                if c.z < z0 {
                    below[at(c.with_z(0))]
                } else {
                    layer[at(c.with_z(c.z - z0))]
                }
            };
            for &v in &vertices {
                let c = v - self.lo;
                let v0 = value(c);
                // Edges to the corners below, behind and left, as from their lower end.
                for axis in [2, 1, 0] {
                    let d = c - IVec3::AXES[axis];
                    if d[axis] < 0 {
                        continue;
                    }
                    let v1 = value(d);
                    if !v1.is_nan() && (v0 < 0.0) != (v1 < 0.0) {
                        edges.push((self.lo + d, axis));
                    }
                }
            }
            below.copy_from_slice(&layer[plane * (z1 - z0) as usize..]);
        }
        edges.sort_unstable_by_key(|&(c, axis)| (c.z, c.y, c.x, axis));
        Ok(edges)
    }

    /// Bits of the block's own corners (x fastest) within the field's support of a sparse
    /// particle.
    fn sparse_neighbourhood(&self, particles: &[Vec3]) -> Vec<u64> {
        let h = self.handlers;
        let (support, r) = (self.field.support(), self.spacing);
        let full = lattice_neighbours(support / r);
        let sparse = (SPARSE * full as f32) as usize;
        let reach = IVec3::splat((support / h.cell_size()).ceil() as i32);
        let side = self.size + 1;
        let mut marked = vec![0u64; (side * side * side) as usize / 64 + 1];
        let (box_lo, box_hi) = (
            self.lo.as_vec3() * self.cell - support,
            (self.lo + self.size).as_vec3() * self.cell + support,
        );
        for &p in particles {
            if p.cmplt(box_lo).any() || p.cmpgt(box_hi).any() {
                continue;
            }
            let cell = h.cell_of(p);
            let mut count = 0usize;
            h.for_each_in_cells(cell - reach, cell + reach, |range| {
                count += h.positions[range]
                    .iter()
                    .filter(|q| (**q - p).length_squared() <= support * support)
                    .count();
            });
            if count >= sparse {
                continue;
            }
            // Row by row, the chord of the ball.
            let q = p / self.cell - self.lo.as_vec3();
            let h = support / self.cell;
            let (z0, z1) = ((q.z - h).ceil() as i32, (q.z + h).floor() as i32);
            for z in z0.max(0)..=z1.min(self.size) {
                let dz = z as f32 - q.z;
                let disk = h * h - dz * dz;
                let (y0, y1) = (
                    (q.y - disk.sqrt()).ceil() as i32,
                    (q.y + disk.sqrt()).floor() as i32,
                );
                for y in y0.max(0)..=y1.min(self.size) {
                    let dy = y as f32 - q.y;
                    let w = (disk - dy * dy).max(0.0).sqrt();
                    let (x0, x1) = ((q.x - w).ceil() as i32, (q.x + w).floor() as i32);
                    let (x0, x1) = (x0.max(0), x1.min(self.size));
                    if x0 <= x1 {
                        let row = ((z * side + y) * side) as usize;
                        set_bits(&mut marked, row + x0 as usize, row + x1 as usize + 1);
                    }
                }
            }
        }
        marked
    }
}

/// Sets bits `start..end`, a word at a time.
fn set_bits(bits: &mut [u64], start: usize, end: usize) {
    let mut i = start;
    while i < end {
        let n = (64 - (i & 63)).min(end - i);
        bits[i >> 6] |= (u64::MAX >> (64 - n)) << (i & 63);
        i += n;
    }
}

/// Points of the unit lattice within `radius` of a lattice point, itself excluded.
fn lattice_neighbours(radius: f32) -> usize {
    let n = radius.floor() as i32;
    let mut count = 0;
    for z in -n..=n {
        for y in -n..=n {
            for x in -n..=n {
                let d2 = (x * x + y * y + z * z) as f32;
                count += usize::from(d2 > 0.0 && d2 <= radius * radius);
            }
        }
    }
    count
}
