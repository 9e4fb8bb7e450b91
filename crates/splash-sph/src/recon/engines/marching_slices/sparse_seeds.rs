//! Seeds around sparse particles for the blobs that walking down from each particle cannot
//! find (Marching Correctors, Sec. III-C: at least one seed per component). Where particles
//! are sparse the field can dip below zero one to three spacings from every particle, around
//! no particle's nearest corner (measured on cbd-small frame 40 at cell r/2: 0.8r to 2.6r).
//! Every corner between r and 3r of a sparse particle is tried. The paper's particle pairs
//! (corners on the segment between two particles within the support) were tried first and
//! found 2 of the 7 blobs there: some lie beside every segment, or between particles farther
//! apart than the support.
//!
//! Only sparse particles seed: in the bulk every negative corner belongs to the fluid around
//! the particles, and seeding there would cost as much as sampling every corner of the fluid.

use glam::{IVec3, Vec3};
use rustc_hash::FxHashSet;

use crate::neighbours::handler_array::HandlerArray;

/// A particle is sparse below this fraction of the neighbours a full lattice of spacing r has
/// within the field's support: surface and splash particles are, bulk particles are not.
const SPARSE: f32 = 0.75;

/// Spacings from a sparse particle within which corners are tried: the farthest blob measured
/// lay 2.6r from its nearest particle.
const SEED_REACH: f32 = 3.0;

/// Where the sparse seeds of one block are looked for.
pub struct SparseSeeds<'a> {
    pub handlers: &'a HandlerArray,
    /// The field's support, and the particle spacing r.
    pub support: f32,
    pub spacing: f32,
    pub cell: f32,
    /// Global index of the block's local corner (0, 0, 0), and the local corners that may seed:
    /// `lo..=hi` on each axis.
    pub origin: IVec3,
    pub lo: IVec3,
    pub hi: IVec3,
}

impl SparseSeeds<'_> {
    /// Local corners between r and 3r of a sparse particle of `particles` (closer corners
    /// belong to the particle's own fluid), each once, in (z, y, x) order.
    pub fn corners(&self, particles: &[Vec3]) -> Vec<IVec3> {
        let h = self.handlers;
        let (support, r) = (self.support, self.spacing);
        let full = lattice_neighbours(support / r);
        let sparse = (SPARSE * full as f32) as usize;
        let reach = IVec3::splat((support / h.cell_size()).ceil() as i32);
        let mut found = FxHashSet::default();
        for &p in particles {
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
            let reach_far = SEED_REACH * r;
            let a = ((p - reach_far) / self.cell).floor().as_ivec3();
            let b = ((p + reach_far) / self.cell).ceil().as_ivec3();
            for z in a.z..=b.z {
                for y in a.y..=b.y {
                    for x in a.x..=b.x {
                        let g = IVec3::new(x, y, z);
                        let d = (g.as_vec3() * self.cell - p).length();
                        let c = g - self.origin;
                        if d >= r
                            && d <= reach_far
                            && c.cmpge(self.lo).all()
                            && c.cmple(self.hi).all()
                        {
                            found.insert(c);
                        }
                    }
                }
            }
        }
        let mut corners: Vec<IVec3> = found.into_iter().collect();
        corners.sort_unstable_by_key(|c| (c.z, c.y, c.x));
        corners
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
