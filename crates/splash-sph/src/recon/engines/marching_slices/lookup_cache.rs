//! The particle lookup cache of Rosenberg & Birdwell 2008, Sec. 6 ("2D projection, 1D
//! lookup"), kept "only over the active slices" as their Sec. 6 and Results propose: it holds
//! the particles within reach of a window of slices around the slab in work, projected onto
//! tiles of `TILE`² columns, each tile listing (in z order) the particles within reach of one
//! of its columns. A lookup scans its tile's particles near the corner's height and keeps
//! exactly those within reach of the corner. When the marching leaves the window, the cache is
//! built again over the next one: it holds a window's particles, not the block's.
//!
//! The particle index doubles as the paper's mid_z, as particles are numbered by height.

use glam::{DVec3, IVec3};

use crate::error::{Error, Result};
use crate::recon::budget;

/// Columns per side of a tile: the per-column lists of the paper take π reach² entries per
/// particle (about 200 at cell r/2), tiles of 4² about 20, for twice as many candidates.
const TILE: i32 = 4;
/// Slices a window serves beyond the first: the cache is built again about every `WINDOW`
/// slices of a sweep.
const WINDOW: i32 = 8;

pub struct LookupCache {
    /// Cubes per side of the block's volume.
    cubes: i32,
    /// Slabs of one reach, rounded up: a particle reaches corners at most this many slices
    /// from its own.
    reach_slabs: i32,
    /// The first particle whose own slab (its height in cubes, rounded down) is at least s.
    slab_start: Vec<u32>,
    /// Below this squared distance minus the squared reach a particle is certainly within
    /// reach, above it certainly not: between, the exact test decides.
    tolerance: f64,
    /// The slices lookups are served at, lo..=hi (empty before the first lookup).
    window: (i32, i32),
    /// The window's first particle.
    first: u32,
    /// From `first` on: the window's particles in cube units, with their squared reach.
    near: Vec<[f64; 4]>,
    /// Tiles per side.
    tiles: usize,
    /// Tile t's particles are `entries[start[t]..start[t + 1]]`.
    start: Vec<u32>,
    entries: Vec<u32>,
    /// Where the tile's last lookup started.
    cursor: Vec<u32>,
    /// Scratch of the insertion.
    fill: Vec<u32>,
    /// The last lookup's particles within reach.
    kept: Vec<u32>,
}

impl LookupCache {
    /// The cache of a block whose corners are 0..=`cubes` on each axis, with particles
    /// `0..len` sorted by z: `particle(i)` is particle i in cube units of the block (world
    /// position / cube size − the block's origin) and its reach in cubes. Columns and slices
    /// on the block's boundary see no particles, which forces the field there to its empty
    /// (outside) value (Sec. 3). All the memory of the largest window is taken here.
    pub fn new(
        len: usize,
        cubes: i32,
        particle: impl Fn(usize) -> (DVec3, f64),
    ) -> Result<LookupCache> {
        let side = cubes as usize + 1;
        let tiles = side.div_ceil(TILE as usize);
        let max_reach = (0..len).map(|i| particle(i).1).fold(0.0, f64::max);
        let tolerance = 1e-6 * (1.0 + max_reach * max_reach);
        let what = || format!("the lookup cache of a block of {side}² columns");
        let mut slab_start = budget::try_vec(side + 1, what)?;
        // Entries of the particles before slab_start[s].
        let mut entries_before = budget::try_vec(side + 1, what)?;
        let (mut i, mut total) = (0, 0u64);
        for s in 0..=side as i32 {
            while i < len && (particle(i).0.z.floor() as i32) < s {
                let (q, r) = particle(i);
                let q = [q.x, q.y, q.z, r.powi(2)];
                for_each_tile(q, cubes, tiles, tolerance, |_| total += 1);
                i += 1;
            }
            slab_start.push(i as u32);
            entries_before.push(total);
        }
        let mut cache = LookupCache {
            cubes,
            reach_slabs: max_reach.ceil() as i32,
            slab_start,
            tolerance,
            window: (1, 0),
            first: 0,
            near: Vec::new(),
            tiles,
            start: budget::try_filled(tiles * tiles + 1, 0, what)?,
            entries: Vec::new(),
            fill: budget::try_filled(tiles * tiles, 0, what)?,
            cursor: budget::try_filled(tiles * tiles, 0, what)?,
            kept: Vec::new(),
        };
        // The fullest window: its particles, and their entries.
        let (mut particles, mut entries) = (0, 0);
        for lo in 1..cubes {
            let (a, b) = cache.particles(lo, lo + WINDOW);
            let slab = |p: u32| cache.slab_start.partition_point(|&s| s < p);
            particles = particles.max(b - a);
            entries = entries.max(entries_before[slab(b)] - entries_before[slab(a)]);
        }
        if entries > u64::from(u32::MAX) {
            return Err(Error::limit(format!(
                "a block of the slices engine would hold {entries} particle entries, more than \
                 {}; use a larger cell or smaller blocks (--block)",
                u32::MAX
            )));
        }
        let entries = entries as usize;
        let what = || format!("the lookup cache's {entries} particle entries");
        budget::try_reserve(&mut cache.entries, entries, what)?;
        budget::try_reserve(&mut cache.near, particles as usize, what)?;
        budget::try_reserve(&mut cache.kept, particles as usize, what)?;
        Ok(cache)
    }

    /// The first particle whose own slab is at least `s`.
    fn slab(&self, s: i32) -> u32 {
        self.slab_start[s.clamp(0, self.cubes + 1) as usize]
    }

    /// The particles within reach of slices lo..=hi: those whose own slab lies within reach
    /// (a particle reaches at most `reach_slabs` cubes, and rounds the ends of its reach
    /// inwards).
    fn particles(&self, lo: i32, hi: i32) -> (u32, u32) {
        let r = self.reach_slabs;
        (self.slab(lo - r), self.slab(hi + r + 1))
    }

    /// The particles within reach of corner `c`, in z order, each with `true` (the lookup is
    /// exact, as Sec. 6 requires). `particle` is as for [`LookupCache::new`].
    pub fn lookup(
        &mut self,
        c: IVec3,
        particle: impl Fn(usize) -> (DVec3, f64),
    ) -> impl ExactSizeIterator<Item = (usize, bool)> + '_ {
        self.kept.clear();
        let inner = 1..self.cubes;
        if inner.contains(&c.x) && inner.contains(&c.y) && inner.contains(&c.z) {
            if !(self.window.0..=self.window.1).contains(&c.z) {
                self.slide(c.z, particle);
            }
            self.keep_within_reach(c);
        }
        self.kept.iter().map(|&p| (p as usize, true))
    }

    fn keep_within_reach(&mut self, c: IVec3) {
        let t = (c.y / TILE) as usize * self.tiles + (c.x / TILE) as usize;
        let (first, end) = (self.start[t] as usize, self.start[t + 1] as usize);
        let (lowest, highest) = self.particles(c.z, c.z);
        // From where the tile's last lookup started: the next, a slice up or down, starts near.
        let mut at = (self.cursor[t] as usize).clamp(first, end);
        while at > first && self.entries[at - 1] >= lowest {
            at -= 1;
        }
        while at < end && self.entries[at] < lowest {
            at += 1;
        }
        self.cursor[t] = at as u32;
        let list = &self.entries[at..end];
        let list = &list[..list.partition_point(|&p| p < highest)];
        let (near, tolerance) = (&self.near[..], self.tolerance);
        let at = c.as_dvec3();
        let excess = |p: u32| {
            let q = near[(p - self.first) as usize];
            (
                (at.x - q[0]).powi(2) + (at.y - q[1]).powi(2) + (at.z - q[2]).powi(2) - q[3],
                q,
            )
        };
        // Branch-free: each particle is written, and the next overwrites it unless it is kept.
        self.kept.resize(list.len(), 0);
        let (mut n, mut unsure) = (0, false);
        for &p in list {
            let (e, _) = excess(p);
            self.kept[n] = p;
            n += usize::from(e < -tolerance);
            unsure |= e.abs() <= tolerance;
        }
        if unsure {
            // A particle about at reach (rare): the exact test for those.
            n = 0;
            for &p in list {
                let (e, q) = excess(p);
                let kept = if e.abs() > tolerance {
                    e < 0.0
                } else {
                    within_reach(q, c)
                };
                self.kept[n] = p;
                n += usize::from(kept);
            }
        }
        self.kept.truncate(n);
    }

    /// Builds the cache over a window holding slice `z` and, ahead of the sweep (up or down),
    /// the next `WINDOW` - 1 slices, and behind it the slice it comes from: the slab in work
    /// reads the slices on both of its sides.
    fn slide(&mut self, z: i32, particle: impl Fn(usize) -> (DVec3, f64)) {
        let (lo, hi) = if z > self.window.1 {
            (z - 1, z - 1 + WINDOW)
        } else {
            (z + 1 - WINDOW, z + 1)
        };
        self.window = (lo.max(1), hi.min(self.cubes - 1));
        let (first, end) = self.particles(self.window.0, self.window.1);
        self.first = first;
        self.near.clear();
        self.near.extend((first..end).map(|i| {
            let (q, r) = particle(i as usize);
            [q.x, q.y, q.z, r.powi(2)]
        }));
        let (cubes, tiles, tolerance) = (self.cubes, self.tiles, self.tolerance);
        self.start.fill(0);
        for &q in &self.near {
            for_each_tile(q, cubes, tiles, tolerance, |t| self.start[t + 1] += 1);
        }
        for t in 0..tiles * tiles {
            self.start[t + 1] += self.start[t];
        }
        self.fill.copy_from_slice(&self.start[..tiles * tiles]);
        self.cursor.copy_from_slice(&self.start[..tiles * tiles]);
        self.entries.resize(self.start[tiles * tiles] as usize, 0);
        for (k, &q) in self.near.iter().enumerate() {
            for_each_tile(q, cubes, tiles, tolerance, |t| {
                self.entries[self.fill[t] as usize] = first + k as u32;
                self.fill[t] += 1;
            });
        }
    }

    /// An upper estimate of [`LookupCache::heap_bytes`] for `particles` reaching `reach` cubes
    /// in a block of `cubes` per side: as if one window held them all.
    pub fn planned_bytes(particles: u64, cubes: i32, reach: f64) -> u64 {
        let side = (cubes.max(0) + 1) as u64;
        let tiles = side.div_ceil(TILE as u64);
        let span = (2.0 * reach / f64::from(TILE)).ceil() as u64 + 1;
        let entries = particles.saturating_mul(span.saturating_mul(span).min(tiles * tiles));
        let near = particles.saturating_mul(size_of::<[f64; 4]>() as u64 + 4);
        near.saturating_add(entries.saturating_mul(4))
            .saturating_add((3 * tiles * tiles + side + 2) * 4)
    }

    /// Bytes held, all taken when the cache is made: the paper's "cache memory".
    pub fn heap_bytes(&self) -> usize {
        self.near.capacity() * size_of::<[f64; 4]>()
            + (self.slab_start.capacity()
                + self.start.capacity()
                + self.entries.capacity()
                + self.fill.capacity()
                + self.cursor.capacity()
                + self.kept.capacity())
                * size_of::<u32>()
    }
}

/// The tiles with a column within reach of particle `q` (position, squared reach) off the
/// block's boundary, each once; a few more at most (within `tolerance`).
fn for_each_tile(q: [f64; 4], cubes: i32, tiles: usize, tolerance: f64, mut f: impl FnMut(usize)) {
    let h2 = q[3];
    let h = h2.sqrt();
    let (x0, x1) = (ceil(q[0] - h).max(1), floor(q[0] + h).min(cubes - 1));
    let (y0, y1) = (ceil(q[1] - h).max(1), floor(q[1] + h).min(cubes - 1));
    // How far v lies outside a..=b.
    let gap = |v: f64, a: i32, b: i32| (f64::from(a) - v).max(v - f64::from(b)).max(0.0);
    for ty in y0 / TILE..=y1 / TILE {
        let dy = gap(q[1], (ty * TILE).max(y0), (ty * TILE + TILE - 1).min(y1));
        for tx in x0 / TILE..=x1 / TILE {
            let dx = gap(q[0], (tx * TILE).max(x0), (tx * TILE + TILE - 1).min(x1));
            if dx * dx + dy * dy <= h2 + tolerance {
                f(ty as usize * tiles + tx as usize);
            }
        }
    }
}

/// Whether particle `q` (position, squared reach) reaches corner `c`, decided as the paper's
/// insertion does: its rows within reach, the chord of its disk on the corner's row, and the
/// slices within reach on the corner's column, each rounded inwards to whole corners.
fn within_reach(q: [f64; 4], c: IVec3) -> bool {
    let (h2, q) = (q[3], DVec3::new(q[0], q[1], q[2]));
    let h = h2.sqrt();
    if c.y < ceil(q.y - h) || c.y > floor(q.y + h) {
        return false;
    }
    let row2 = h2 - (f64::from(c.y) - q.y).powi(2);
    if row2 < 0.0 {
        return false;
    }
    let w = row2.sqrt();
    if c.x < ceil(q.x - w) || c.x > floor(q.x + w) {
        return false;
    }
    let d2 = (f64::from(c.x) - q.x).powi(2) + (f64::from(c.y) - q.y).powi(2);
    if d2 > h2 {
        return false;
    }
    let hz = (h2 - d2).sqrt();
    ceil(q.z - hz) <= c.z && c.z <= floor(q.z + hz)
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

    /// Random particles in a block of 20 cubes, reaching 2 to 3.3 cubes: every corner's lookup
    /// equals the brute-force set within reach (boundary corners: none), sweeping the block
    /// up, down and at random heights, so that the window moves every way.
    #[test]
    fn lookups_return_exactly_the_particles_within_reach() {
        let mut seed = 5u32;
        let mut next = || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            f64::from(seed >> 8) / f64::from(1u32 << 24)
        };
        let cubes = 20;
        let mut ps: Vec<(DVec3, f64)> = (0..300)
            .map(|_| {
                (
                    DVec3::new(next(), next(), next()) * 16.0 + 2.0,
                    2.0 + next() * 1.3,
                )
            })
            .collect();
        // Some particles exactly at reach of corners.
        ps.extend((0..5).map(|k| (DVec3::new(10.0, 10.0, 4.0 + 3.0 * f64::from(k)), 3.0)));
        ps.sort_by(|a, b| a.0.z.total_cmp(&b.0.z));
        let particle = |i: usize| ps[i];
        let mut cache = LookupCache::new(ps.len(), cubes, particle).unwrap();
        let bytes = cache.heap_bytes();
        let random: Vec<i32> = (0..=cubes).map(|_| (next() * 21.0) as i32).collect();
        let mut found = Vec::new();
        for pass in 0..3 {
            for y in 0..=cubes {
                for x in 0..=cubes {
                    for k in 0..=cubes {
                        let z = [k, cubes - k, random[k as usize]][pass];
                        let c = IVec3::new(x, y, z);
                        found.clear();
                        found.extend(cache.lookup(c, particle).map(|p| p.0));
                        let boundary = c.min_element() == 0 || c.max_element() == cubes;
                        let expected: Vec<usize> = (0..ps.len())
                            .filter(|&i| {
                                let (q, r) = ps[i];
                                !boundary && q.distance(c.as_dvec3()) <= r
                            })
                            .collect();
                        assert_eq!(found, expected, "corner {c}");
                    }
                }
            }
        }
        assert_eq!(cache.heap_bytes(), bytes, "memory taken up front");
    }
}
