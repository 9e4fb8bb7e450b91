//! The particle lookup cache of Rosenberg & Birdwell 2008, Sec. 6 ("2D projection, 1D
//! lookup"): the projection slice holds, per column (x, y) of corners, one entry for each
//! particle within reach of some corner of the column, with the range of slices min_z..=max_z
//! where it is. A lookup scans the column's entries of particles near its height and keeps
//! those whose range holds it: exactly the particles within reach, none outside.
//!
//! Entries are stored column by column in one array (the paper's linked lists, flattened), in
//! the particles' z order; the particle index doubles as the paper's mid_z, as particles are
//! numbered by height.

use glam::{DVec3, IVec3};

use crate::error::{Error, Result};
use crate::recon::budget;

/// One particle's influence on one column.
#[derive(Debug, Clone, Copy)]
struct Entry {
    particle: u32,
    min_z: u16,
    max_z: u16,
}

pub struct LookupCache {
    /// Corners per side of the block's volume.
    side: usize,
    /// Slabs of one reach, rounded up: a particle reaches corners at most this many slices
    /// from its own.
    reach_slabs: i32,
    /// Column c's entries are `entries[start[c]..start[c + 1]]`.
    start: Vec<u32>,
    entries: Vec<Entry>,
    /// Where the column's last lookup started: the next, a slice up or down, starts nearby.
    cursor: Vec<u32>,
    /// The first particle whose own slab (its height in cubes, rounded down) is at least s.
    slab_start: Vec<u32>,
}

impl LookupCache {
    /// The cache of `particles`, sorted by z, in cube units of a block whose corners are
    /// 0..=`cubes` on each axis (`particles` = world position / cube size − the block's
    /// origin), each reaching `reach(i)` cubes. Columns and slices on the block's boundary
    /// get no entries, which forces the field there to its empty (outside) value (Sec. 3).
    pub fn build(
        particles: &[DVec3],
        cubes: i32,
        reach: impl Fn(usize) -> f64,
    ) -> Result<LookupCache> {
        let side = cubes as usize + 1;
        let max_reach = (0..particles.len()).map(&reach).fold(0.0, f64::max);
        let what = || format!("the lookup cache of a block of {side}² columns");
        let mut counts = budget::try_filled(side * side + 1, 0u32, what)?;
        for_each_entry(particles, cubes, &reach, |column, _| counts[column] += 1);
        let mut start = budget::try_vec(counts.len(), what)?;
        let mut total = 0u32;
        for &c in &counts {
            start.push(total);
            total = total.checked_add(c).ok_or_else(|| {
                Error::limit(format!(
                    "a block of the slices engine would hold more than {} particle entries; \
                     use a larger cell or smaller blocks (--block)",
                    u32::MAX
                ))
            })?;
        }
        drop(counts);
        let mut fill = start.clone();
        let entry = Entry {
            particle: 0,
            min_z: 0,
            max_z: 0,
        };
        let mut entries = budget::try_filled(total as usize, entry, || {
            format!("the lookup cache's {total} particle entries")
        })?;
        for_each_entry(particles, cubes, &reach, |column, entry| {
            entries[fill[column] as usize] = entry;
            fill[column] += 1;
        });
        let mut slab_start = Vec::with_capacity(side + 1);
        let mut i = 0;
        for s in 0..=side as i32 {
            while i < particles.len() && (particles[i].z.floor() as i32) < s {
                i += 1;
            }
            slab_start.push(i as u32);
        }
        Ok(LookupCache {
            side,
            reach_slabs: max_reach.ceil() as i32,
            cursor: start.clone(),
            start,
            entries,
            slab_start,
        })
    }

    /// The particles near corner `c`'s height in its column, in z order, each with whether it
    /// is within reach of `c`: all those within reach are among them.
    pub fn lookup(&mut self, c: IVec3) -> impl ExactSizeIterator<Item = (usize, bool)> + '_ {
        let column = c.y as usize * self.side + c.x as usize;
        let (first, end) = (self.start[column], self.start[column + 1]);
        // Particles whose own slab lies within reach (plus one for rounding) of c.z.
        let slab = |s: i32| self.slab_start[s.clamp(0, self.side as i32) as usize];
        let (lowest, highest) = (
            slab(c.z - self.reach_slabs - 1),
            slab(c.z + self.reach_slabs + 2),
        );
        let mut at = self.cursor[column].clamp(first, end);
        while at > first && self.entries[at as usize - 1].particle >= lowest {
            at -= 1;
        }
        while at < end && self.entries[at as usize].particle < lowest {
            at += 1;
        }
        self.cursor[column] = at;
        let window = &self.entries[at as usize..end as usize];
        let len = window.partition_point(|e| e.particle < highest);
        let z = c.z as u16;
        window[..len]
            .iter()
            .map(move |e| (e.particle as usize, e.min_z <= z && z <= e.max_z))
    }

    /// Bytes held: the paper's "cache memory".
    pub fn heap_bytes(&self) -> usize {
        self.entries.capacity() * size_of::<Entry>()
            + (self.start.capacity() + self.cursor.capacity() + self.slab_start.capacity())
                * size_of::<u32>()
    }
}

/// The column and entry of every particle's influence: columns within its reach, each with
/// the slices within reach on that column, all clamped off the block's boundary.
fn for_each_entry(
    particles: &[DVec3],
    cubes: i32,
    reach: impl Fn(usize) -> f64,
    mut f: impl FnMut(usize, Entry),
) {
    let side = cubes as usize + 1;
    let (lo_in, hi_in) = (1, cubes - 1);
    for (i, q) in particles.iter().enumerate() {
        let h2 = reach(i).powi(2);
        let h = h2.sqrt();
        let (y0, y1) = (ceil(q.y - h).max(lo_in), floor(q.y + h).min(hi_in));
        for y in y0..=y1 {
            // The row's columns within reach: a chord of the disk.
            let row2 = h2 - (f64::from(y) - q.y).powi(2);
            if row2 < 0.0 {
                continue;
            }
            let w = row2.sqrt();
            let (x0, x1) = (ceil(q.x - w).max(lo_in), floor(q.x + w).min(hi_in));
            for x in x0..=x1 {
                let d2 = (f64::from(x) - q.x).powi(2) + (f64::from(y) - q.y).powi(2);
                if d2 > h2 {
                    continue;
                }
                let hz = (h2 - d2).sqrt();
                let (lo, hi) = (ceil(q.z - hz).max(lo_in), floor(q.z + hz).min(hi_in));
                if lo > hi {
                    continue;
                }
                let entry = Entry {
                    particle: i as u32,
                    min_z: lo as u16,
                    max_z: hi as u16,
                };
                f(y as usize * side + x as usize, entry);
            }
        }
    }
}

/// ⌊v⌋ and ⌈v⌉ without a libm call (the baseline x86-64 target has no SSE4.1 rounding).
fn floor(v: f64) -> i32 {
    let i = v as i32;
    i - i32::from(v < f64::from(i))
}

fn ceil(v: f64) -> i32 {
    let i = v as i32;
    i + i32::from(v > f64::from(i))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Random particles in a block of 20 cubes, reach 3.3 cubes: every corner's lookup equals
    /// the brute-force set within reach (boundary corners: none).
    #[test]
    fn lookups_return_exactly_the_particles_within_reach() {
        let mut seed = 5u32;
        let mut next = || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            f64::from(seed >> 8) / f64::from(1u32 << 24)
        };
        let cubes = 20;
        let mut ps: Vec<DVec3> = (0..300)
            .map(|_| DVec3::new(next(), next(), next()) * 16.0 + 2.0)
            .collect();
        ps.sort_by(|a, b| a.z.total_cmp(&b.z));
        let reach = 3.3;
        let mut cache = LookupCache::build(&ps, cubes, |_| reach).unwrap();
        let mut found = Vec::new();
        // Up and down each column, as the marching does, to move the cursors both ways.
        for pass in [false, true] {
            for y in 0..=cubes {
                for x in 0..=cubes {
                    for k in 0..=cubes {
                        let z = if pass { cubes - k } else { k };
                        let c = IVec3::new(x, y, z);
                        found.clear();
                        found.extend(cache.lookup(c).filter(|p| p.1).map(|p| p.0));
                        let boundary = c.min_element() == 0 || c.max_element() == cubes;
                        let expected: Vec<usize> = (0..ps.len())
                            .filter(|&i| !boundary && ps[i].distance(c.as_dvec3()) <= reach)
                            .collect();
                        assert_eq!(found, expected, "corner {c}");
                    }
                }
            }
        }
    }
}
