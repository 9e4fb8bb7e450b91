//! Estimates the particle spacing `r` (the equilibrium distance between SPH particles) when the
//! user gives neither `--spacing` nor `--particle-radius`.

use glam::Vec3;
use rayon::prelude::*;

use crate::neighbours::bucket_grid::{BucketGrid, Nearest};

/// Cells per axis stay below 2^20 + 1 so that a cell's coordinates pack into 21 bits each for
/// hashing, and shells stay bounded whatever the outliers.
const MAX_CELLS_PER_AXIS: f32 = (1 << 20) as f32;

/// Size of the stratified subset that sizes the grid cells, and how many of its particles are
/// queried to do so.
const POOL: usize = 1 << 14;
const POOL_QUERIES: usize = 64;

/// Radius of the balls that measure the density, in median nearest-neighbour distances: wide
/// enough to hold 50–120 particles in a 3-D fluid or lattice, so counts vary little, narrow
/// enough that a quarter of the samples lie deeper than it in any sizeable body of fluid.
const BALL: f32 = 3.0;

/// The balls' edge is soft: a neighbour's weight falls linearly in squared distance from 1 at
/// `(1 - SOFT) * radius` to 0 at `(1 + SOFT) * radius`. A hard edge at 3 spacings of a cubic
/// lattice lies exactly on a shell of 30 lattice points, and the estimate would jump by 7% with
/// rounding.
const SOFT: f32 = 0.2;

/// Below this local dimension the particles don't fill 3-D space (see [`estimate_spacing`]).
const MIN_DIMENSION: f32 = 2.5;

/// At most this many samples measure the density: each costs a few hundred scattered memory
/// accesses, and on the real frames the upper quartile of 2048 counts gives the spacing within
/// 0.2% of 40,000.
const DENSITY_SAMPLES: usize = 2048;

/// The particle spacing `r` (the SPH equilibrium distance), from the local number density of
/// the particles; None when fewer than 2 particles have finite coordinates or all of those
/// coincide.
///
/// Samples are deterministic (one particle from each of equal slices of the array, so the same
/// input gives the same answer):
///
/// 1. `d` = the median distance from each of at most 20,000 samples to its nearest
///    neighbour.
/// 2. For each of at most 2,048 samples, `count` = the number of particles
///    within `3 d` of it, itself included. The ball's edge is slightly soft (weights fall
///    linearly in squared distance from 1 at `2.4 d` to 0 at `3.6 d`): with a hard edge, the
///    shell of 30 neighbours at exactly `3 d` on a cubic lattice would swing the estimate by
///    7%. Each particle owns `V / count` of space, where `V` is the ball's volume (the integral
///    of the weights), so the spacing is `(V / count)^(1/3)`, taking the upper quartile of
///    `count` over the samples. Particles near the surface have partly empty balls and low
///    counts; the upper quartile leaves them out as long as a quarter of the samples lie deeper
///    than `3 d`.
/// 3. Fallback rule: the result is `d` instead when the particles don't fill 3-D space. The
///    test is the local dimension `log2(count(3 d) / count(1.5 d))`, both counts being upper
///    quartiles over the same samples: about 3 in a body of fluid, 2 on a sheet or a slab two
///    particles thick, 1 on a line, and lower still when there are too few particles to fill
///    the ball (two particles always fall back, giving their distance; a lattice block of
///    7 × 7 × 7 particles falls back, one of 8 × 8 × 8 doesn't). Below 2.5 the result is `d`.
///
/// On the SPlisHSPlasH frames in `shared/data` the estimate is within 2% of the simulator's
/// spacing (0.1% on the large frame), where `d` alone is 0.78–0.86 `r` in settled, disordered
/// fluid (exact only on a lattice). Near the threshold the estimate is rough either way:
/// structures that pass the test with few samples deep inside (slabs or rods 3–5 particles
/// thick, blocks of 100–1000 particles) come out up to ~15% large, and the fallback `d` is
/// 15–25% small for disordered particles.
///
/// Distances of exactly 0 are skipped, and coincident particles count once: a duplicate says
/// nothing about the spacing. Particles with non-finite coordinates are ignored.
pub fn estimate_spacing(particles: &[Vec3]) -> Option<f32> {
    estimate_sampled(particles, SAMPLES)
}

/// Particles sampled by [`estimate_spacing`]: enough for 1% on the shared frames, and a few
/// milliseconds on a million particles.
const SAMPLES: usize = 20_000;

/// [`estimate_spacing`] from fewer samples, enough to tell a given spacing that is off by a
/// factor of 2 (the sanity check of every first frame, which the full estimate made cost
/// 10 % of a 44 k-particle frame).
pub(crate) fn rough_spacing(particles: &[Vec3]) -> Option<f32> {
    estimate_with(particles, ROUGH_SAMPLES, ROUGH_LOAD)
}

const ROUGH_SAMPLES: usize = 512;

/// Particles per bucket of the grids: few collisions for the full estimate's 20,000 queries;
/// for the rough one's 512 a smaller table that builds faster (on 1 M particles 3x faster
/// than at 2, while its queries take 4 ms).
const LOAD: usize = 2;
const ROUGH_LOAD: usize = 16;

/// [`estimate_spacing`] from at most `max_samples` particles.
fn estimate_sampled(particles: &[Vec3], max_samples: usize) -> Option<f32> {
    estimate_with(particles, max_samples, LOAD)
}

/// [`estimate_sampled`] on grids of `load` particles per bucket.
fn estimate_with(particles: &[Vec3], max_samples: usize, load: usize) -> Option<f32> {
    let grid = grid_for(particles, load)?;
    let nearest = median_nearest(&grid, particles, max_samples)?;
    Some(
        density_spacing(
            &grid,
            particles,
            max_samples.min(DENSITY_SAMPLES),
            BALL * nearest,
        )
        .unwrap_or(nearest),
    )
}

/// `count` items (at least one, at most all) spread evenly through `items`, in order: one from
/// each of `count` equal consecutive slices, at a pseudo-random but fixed position within it.
/// A fixed stride could fall in step with the particles' order (every sample from the same
/// layer of a block, say); the position within the slice breaks that.
fn stratified<T: Copy>(items: &[T], count: usize) -> impl Iterator<Item = T> {
    let n = items.len();
    let count = count.max(1).min(n);
    (0..count).map(move |i| {
        let (start, end) = (i * n / count, (i + 1) * n / count);
        // splitmix64 finaliser
        let mut h = (i as u64).wrapping_add(0x9E37_79B9_7F4A_7C15);
        h = (h ^ (h >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        h = (h ^ (h >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        h ^= h >> 31;
        items[start + (h % (end - start) as u64) as usize]
    })
}

fn median(mut values: Vec<f32>) -> Option<f32> {
    if values.is_empty() {
        return None;
    }
    let mid = values.len() / 2;
    Some(*values.select_nth_unstable_by(mid, f32::total_cmp).1)
}

/// The value a quarter of `values` lie above (or at); None when empty.
fn upper_quartile(mut values: Vec<f32>) -> Option<f32> {
    if values.is_empty() {
        return None;
    }
    let at = values.len() * 3 / 4;
    Some(*values.select_nth_unstable_by(at, f32::total_cmp).1)
}

/// A grid sized for nearest-neighbour queries on `particles`, `load` of them per bucket; None
/// when fewer than two of them are finite or all of those coincide.
fn grid_for(particles: &[Vec3], load: usize) -> Option<BucketGrid> {
    let (min, max, finite) = particles
        .par_iter()
        .filter(|p| p.is_finite())
        .fold(
            || (Vec3::INFINITY, Vec3::NEG_INFINITY, 0usize),
            |(lo, hi, n), &p| (lo.min(p), hi.max(p), n + 1),
        )
        .reduce(
            || (Vec3::INFINITY, Vec3::NEG_INFINITY, 0),
            |a, b| (a.0.min(b.0), a.1.max(b.1), a.2 + b.2),
        );
    let extent = max - min;
    let largest = extent.max_element();
    if finite < 2 || largest <= 0.0 {
        return None;
    }
    let min_cell = largest / MAX_CELLS_PER_AXIS;

    // Axes much thinner than the box (a sheet, a line) don't count as dimensions, or the
    // volume would vanish and density scaling would use the wrong power.
    let thin = largest * 1e-3;
    let (volume, dims) = extent
        .to_array()
        .iter()
        .filter(|&&e| e > thin)
        .fold((1.0f64, 0i32), |(v, d), &e| (v * f64::from(e), d + 1));
    let spread = |count: usize| (volume / count as f64).powf(1.0 / f64::from(dims)) as f32;

    // Cells of about twice the spacing hold ~8 particles and usually settle a query within
    // the first shell. The bounding box alone misjudges the spacing when the particles fill
    // little of it (fluid in a corner, far outliers), so size the cells from the nearest
    // neighbours in a stratified subset instead, scaled from its density to the full one.
    let pool: Vec<Vec3> = stratified(particles, POOL)
        .filter(|p| p.is_finite())
        .collect();
    let pool_grid = BucketGrid::new(
        &pool,
        pool.len(),
        min,
        extent,
        (2.0 * spread(pool.len())).max(min_cell),
        load,
    );
    let cell = match median_nearest(&pool_grid, &pool, POOL_QUERIES) {
        Some(d) => 2.0 * d * (pool.len() as f32 / finite as f32).powf(1.0 / dims as f32),
        None => 2.0 * spread(finite),
    };
    drop(pool_grid);
    Some(BucketGrid::new(
        particles,
        finite,
        min,
        extent,
        cell.max(min_cell),
        load,
    ))
}

/// Shells a nearest-neighbour search of [`median_nearest`] goes before it gives up.
const NEAREST_SHELLS: i32 = 2;

/// `median(nearest_distances(..))`, without finishing the searches that cannot change it: the
/// searches stop after a few shells, and only those whose lower bound lies below the median
/// of the rest (taking them as infinite) are run to the end. Isolated particles (spray, far
/// outliers) each cost a full scan otherwise.
fn median_nearest(grid: &BucketGrid, particles: &[Vec3], max_samples: usize) -> Option<f32> {
    let samples: Vec<Vec3> = stratified(particles, max_samples)
        .filter(|p| p.is_finite())
        .collect();
    let mut found: Vec<Nearest> = samples
        .par_iter()
        .map(|&p| grid.nearest_within(p, NEAREST_SHELLS))
        .collect();
    // A sample without any other particle means every finite particle coincides with it, so
    // all samples have none; else every search finds one when run to the end.
    if !found.iter().any(|n| matches!(n, Nearest::Found(_))) {
        return median(nearest_distances(grid, particles, max_samples));
    }
    loop {
        let as_found = |n: &Nearest| match *n {
            Nearest::Found(d) => d,
            _ => f32::INFINITY,
        };
        let m = median(found.iter().map(as_found).collect())?;
        let open: Vec<usize> = (0..found.len())
            .filter(|&i| matches!(found[i], Nearest::AtLeast(b) if b < m))
            .collect();
        if open.is_empty() {
            return Some(m.sqrt());
        }
        // Finishing a search only lowers the median: the bounds left stay above it.
        let exact: Vec<Nearest> = open
            .par_iter()
            .map(|&i| grid.nearest_within(samples[i], i32::MAX))
            .collect();
        for (&i, n) in open.iter().zip(exact) {
            found[i] = n;
        }
    }
}

/// Nearest non-zero distance from each of at most `max_samples` stratified samples.
fn nearest_distances(grid: &BucketGrid, particles: &[Vec3], max_samples: usize) -> Vec<f32> {
    let samples: Vec<Vec3> = stratified(particles, max_samples).collect();
    samples
        .par_iter()
        .filter(|p| p.is_finite())
        .filter_map(|&p| grid.nearest(p).map(f32::sqrt))
        .collect()
}

/// The spacing from the upper-quartile particle count in balls of `radius` around the
/// samples; None when the counts don't grow like a 3-D volume (see [`estimate_spacing`]).
fn density_spacing(
    grid: &BucketGrid,
    particles: &[Vec3],
    max_samples: usize,
    radius: f32,
) -> Option<f32> {
    let counts = ball_counts(grid, particles, max_samples, radius);
    let full = upper_quartile(counts.iter().map(|c| c[0]).collect())?;
    let half = upper_quartile(counts.iter().map(|c| c[1]).collect())?;
    let dimension = (full / half).log2();
    // Scaled from the unit ball, so that tiny radii don't underflow when cubed.
    let spacing = radius * (Ball::unit_volume() / full).cbrt();
    (dimension >= MIN_DIMENSION && spacing.is_normal()).then_some(spacing)
}

/// Soft counts of the distinct positions within `radius` and `radius / 2` of each of at most
/// `max_samples` stratified samples, the sample itself included.
fn ball_counts(
    grid: &BucketGrid,
    particles: &[Vec3],
    max_samples: usize,
    radius: f32,
) -> Vec<[f32; 2]> {
    let full = Ball::new(radius);
    let half = Ball::new(radius / 2.0);
    let samples: Vec<Vec3> = stratified(particles, max_samples).collect();
    samples
        .par_iter()
        .filter(|p| p.is_finite())
        .map_init(Vec::new, |crowded: &mut Vec<Vec3>, &p| {
            let mut counts = [1.0, 1.0];
            let mut add = |d: f32| {
                counts[0] += full.weight(d);
                counts[1] += half.weight(d);
            };
            // Particles of `cell` (all of them when None) in bucket `b` and in the ball. A
            // bucket may hold several cells of the ball's box: each particle counts only from
            // its own. Coincident particles share a cell, so a bucket: they count once.
            let mut count = |b: usize, cell: Option<[i32; 3]>| {
                let points = grid.bucket_points(b);
                let inside = |q: Vec3| {
                    let d = q.distance_squared(p);
                    let own = cell.is_none_or(|c| grid.cell_of(q) == c);
                    (d > 0.0 && d < full.outer && own).then_some(d)
                };
                if points.len() <= CROWDED {
                    for (i, &q) in points.iter().enumerate() {
                        if let Some(d) = inside(q)
                            && !points[..i].contains(&q)
                        {
                            add(d);
                        }
                    }
                } else {
                    // Sorted, so that a clump of coincident particles doesn't take a
                    // quadratic search.
                    crowded.clear();
                    crowded.extend(points.iter().copied().filter(|&q| inside(q).is_some()));
                    crowded.sort_unstable_by(lexicographic);
                    crowded.dedup();
                    crowded.iter().for_each(|&q| add(q.distance_squared(p)));
                }
            };
            let lo = grid.cell_of(p - full.reach);
            let hi = grid.cell_of(p + full.reach);
            let cells: u64 = (0..3).map(|a| (hi[a] - lo[a] + 1) as u64).product();
            if cells > grid.occupied as u64 {
                // Cells tiny next to the ball (outliers stretched the grid): cheaper to
                // scan everything.
                (0..grid.buckets()).for_each(|b| count(b, None));
            } else {
                // Particles in a cell `k` cells from `p`'s along an axis are at least
                // `k - 1` cells away along it: skip the columns, and the ends of columns,
                // that lie wholly outside the ball.
                let c = grid.cell_of(p);
                let gap = |a: usize, i: i32| ((i - c[a]).abs() - 1).max(0) as f32 * grid.cell;
                for x in lo[0]..=hi[0] {
                    for y in lo[1]..=hi[1] {
                        let column = gap(0, x).powi(2) + gap(1, y).powi(2);
                        if column >= full.outer {
                            continue;
                        }
                        let k = ((full.outer - column).sqrt() / grid.cell) as i32 + 1;
                        for z in lo[2].max(c[2] - k)..=hi[2].min(c[2] + k) {
                            count(grid.bucket([x, y, z]), Some([x, y, z]));
                        }
                    }
                }
            }
            counts
        })
        .collect()
}

/// Buckets with more particles than this are deduplicated by sorting.
const CROWDED: usize = 32;

/// Orders finite points by x, then y, then z; -0 and 0 compare equal, as under `==`.
fn lexicographic(a: &Vec3, b: &Vec3) -> std::cmp::Ordering {
    let axis = |u: f32, v: f32| u.partial_cmp(&v).unwrap_or(std::cmp::Ordering::Equal);
    axis(a.x, b.x).then(axis(a.y, b.y)).then(axis(a.z, b.z))
}

/// A ball with a soft edge (see [`SOFT`]), in squared distances.
struct Ball {
    inner: f32,
    outer: f32,
    /// The radius beyond which weights are 0.
    reach: f32,
}

impl Ball {
    fn new(radius: f32) -> Self {
        Self {
            inner: ((1.0 - SOFT) * radius).powi(2),
            outer: ((1.0 + SOFT) * radius).powi(2),
            reach: (1.0 + SOFT) * radius,
        }
    }

    fn weight(&self, squared_distance: f32) -> f32 {
        ((self.outer - squared_distance) / (self.outer - self.inner)).clamp(0.0, 1.0)
    }

    /// The integral of the weight over space for a radius of 1: ∫ 4π s² w(s) ds with w = 1 up
    /// to `a` and `(b² - s²) / (b² - a²)` from `a` to `b`.
    fn unit_volume() -> f32 {
        let (a, b) = (1.0 - SOFT, 1.0 + SOFT);
        let ramp = (b * b * (b.powi(3) - a.powi(3)) / 3.0 - (b.powi(5) - a.powi(5)) / 5.0)
            / (b * b - a * a);
        4.0 * std::f32::consts::PI * (a.powi(3) / 3.0 + ramp)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Instant;

    /// Deterministic pseudo-random numbers in [-1, 1) (xorshift), so tests need no crate.
    struct Noise(u64);

    impl Noise {
        fn next(&mut self) -> f32 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 40) as f32 / (1u64 << 23) as f32 - 1.0
        }

        fn vec(&mut self) -> Vec3 {
            Vec3::new(self.next(), self.next(), self.next())
        }
    }

    /// `nx * ny * nz` lattice of spacing `r` with each particle moved by up to `jitter * r` per
    /// axis.
    fn lattice(n: [usize; 3], r: f32, jitter: f32) -> Vec<Vec3> {
        let mut noise = Noise(0x9E37_79B9_7F4A_7C15);
        let mut out = Vec::with_capacity(n[0] * n[1] * n[2]);
        for x in 0..n[0] {
            for y in 0..n[1] {
                for z in 0..n[2] {
                    let p = Vec3::new(x as f32, y as f32, z as f32) * r;
                    out.push(p + noise.vec() * jitter * r);
                }
            }
        }
        out
    }

    fn assert_close(estimate: Option<f32>, expected: f32, tolerance: f32) {
        let e = estimate.expect("an estimate");
        assert!(
            (e / expected - 1.0).abs() <= tolerance,
            "estimate {e}, expected {expected} within {tolerance}"
        );
    }

    /// The median nearest-neighbour distance: what the estimate falls back to.
    fn nearest_median(particles: &[Vec3], max_samples: usize) -> Option<f32> {
        median(nearest_distances(
            &grid_for(particles, LOAD)?,
            particles,
            max_samples,
        ))
    }

    #[test]
    fn jittered_lattice() {
        let particles = lattice([30, 25, 20], 0.014, 0.02);
        assert_close(estimate_sampled(&particles, 10_000), 0.014, 0.03);
        // Deterministic: same input, same answer.
        assert_eq!(
            estimate_sampled(&particles, 1000),
            estimate_sampled(&particles, 1000)
        );
    }

    #[test]
    fn disordered_block() {
        // Particles moved by up to 0.3 r per axis: nearest neighbours at 0.75 r, as in a settled
        // SPH fluid, but the density is still one particle per r³.
        let particles = lattice([30, 30, 30], 0.01, 0.3);
        let nearest = nearest_median(&particles, 10_000).unwrap();
        assert!((0.72..0.78).contains(&(nearest / 0.01)), "{nearest}");
        assert_close(estimate_sampled(&particles, 10_000), 0.01, 0.01);
    }

    #[test]
    fn lattice_far_off_origin() {
        let particles: Vec<Vec3> = lattice([20, 20, 20], 0.014, 0.02)
            .into_iter()
            .map(|p| p + Vec3::new(100.0, -50.0, 20.0))
            .collect();
        assert_close(estimate_sampled(&particles, 10_000), 0.014, 0.03);
    }

    #[test]
    fn far_outliers_are_ignored() {
        let mut particles = lattice([20, 20, 20], 0.014, 0.02);
        particles.extend([
            Vec3::splat(1000.0),
            Vec3::new(-500.0, 3.0, 0.0),
            Vec3::new(0.1, 0.1, 800.0),
            Vec3::new(0.1, -2000.0, 0.1),
            Vec3::new(5.0, 5.0, 5.0),
        ]);
        // Every particle sampled, outliers included: they take the brute-force path.
        assert_close(estimate_sampled(&particles, usize::MAX), 0.014, 0.03);
        assert_close(estimate_sampled(&particles, 500), 0.014, 0.03);
    }

    #[test]
    fn fluid_in_a_corner_of_a_big_box() {
        // A dense block plus a sparse spray over a box 50 times wider.
        let mut particles = lattice([20, 20, 20], 0.01, 0.02);
        let mut noise = Noise(7);
        particles.extend((0..200).map(|_| (noise.vec() + 1.0) * 5.0));
        assert_close(estimate_sampled(&particles, 10_000), 0.01, 0.03);
    }

    #[test]
    fn flat_sheet_and_line() {
        let sheet: Vec<Vec3> = lattice([60, 50, 1], 0.014, 0.02)
            .into_iter()
            .map(|p| Vec3::new(p.x, p.y, 0.3))
            .collect();
        assert_close(estimate_sampled(&sheet, 10_000), 0.014, 0.03);
        let line: Vec<Vec3> = (0..1000).map(|i| Vec3::X * (i as f32 * 0.02)).collect();
        assert_close(estimate_sampled(&line, 10_000), 0.02, 1e-4);
    }

    #[test]
    fn not_filling_space_falls_back_to_nearest_neighbours() {
        // A slab two particles thick, a rod 3 × 3 particles across, a 5 × 5 × 5 block, and a
        // gas of scattered particles: the balls are mostly empty, the density says little.
        let mut noise = Noise(99);
        let gas: Vec<Vec3> = (0..20_000).map(|_| noise.vec()).collect();
        for (name, particles) in [
            ("slab", lattice([100, 100, 2], 0.01, 0.02)),
            ("disordered slab", lattice([100, 100, 2], 0.01, 0.3)),
            ("rod", lattice([1000, 3, 3], 0.01, 0.02)),
            ("small block", lattice([5, 5, 5], 0.01, 0.1)),
            ("gas", gas),
        ] {
            let nearest = nearest_median(&particles, 10_000);
            assert!(nearest.is_some(), "{name}");
            assert_eq!(estimate_sampled(&particles, 10_000), nearest, "{name}");
        }
        // Thick enough: the density again.
        let slab = lattice([100, 100, 8], 0.01, 0.3);
        assert_close(estimate_sampled(&slab, 10_000), 0.01, 0.02);
    }

    #[test]
    fn samples_are_stratified() {
        let items: Vec<usize> = (0..100).collect();
        let pick = |count| stratified(&items, count).collect::<Vec<_>>();
        for count in [1, 3, 7, 10, 33, 99] {
            let picked = pick(count);
            assert_eq!(picked.len(), count);
            // One from each slice.
            for (i, &p) in picked.iter().enumerate() {
                assert!((i * 100 / count..(i + 1) * 100 / count).contains(&p));
            }
        }
        // Not in step with a stride: a lattice's layers all get sampled.
        assert!(pick(10).iter().any(|&p| p % 10 != 0));
        assert_eq!(pick(0).len(), 1);
        assert_eq!(pick(100), items);
        assert_eq!(pick(usize::MAX), items);
    }

    #[test]
    fn tiny_inputs() {
        assert_eq!(estimate_sampled(&[], 100), None);
        assert_eq!(estimate_sampled(&[Vec3::ONE], 100), None);
        assert_eq!(estimate_sampled(&[Vec3::ONE; 5], 100), None);
        let two = [Vec3::new(1.0, 2.0, 3.0), Vec3::new(1.0, 2.0, 3.5)];
        assert_eq!(estimate_sampled(&two, 100), Some(0.5));
        assert_eq!(estimate_sampled(&two, 0), Some(0.5));
        let with_nan = [two[0], Vec3::NAN, two[1]];
        assert_eq!(estimate_sampled(&with_nan, 100), Some(0.5));
    }

    #[test]
    fn duplicates_are_skipped() {
        // Every particle doubled: the zero distances to the twins don't count, and the twins
        // don't double the density.
        let single = lattice([30, 30, 30], 0.05, 0.0);
        let doubled: Vec<Vec3> = single.iter().flat_map(|&p| [p, p]).collect();
        assert_close(estimate_sampled(&doubled, 10_000), 0.05, 0.002);
        assert_eq!(
            nearest_median(&doubled, 10_000),
            nearest_median(&single, 10_000)
        );
    }

    #[test]
    fn clump_of_coincident_particles() {
        // Inactive particles parked at one point, as some simulators write them: counted once,
        // and cheaply.
        let mut particles = lattice([30, 30, 30], 0.01, 0.02);
        particles.extend([Vec3::splat(0.15); 20_000]);
        let start = Instant::now();
        let estimate = estimate_sampled(&particles, 10_000);
        eprintln!("clump: {estimate:?} in {:?}", start.elapsed());
        assert_close(estimate, 0.01, 0.03);
    }

    /// Nearest non-zero distances computed the slow way, for the same samples.
    fn brute_force(particles: &[Vec3], max_samples: usize) -> Vec<f32> {
        let samples: Vec<Vec3> = stratified(particles, max_samples).collect();
        samples
            .par_iter()
            .filter(|p| p.is_finite())
            .filter_map(|&p| {
                let nearest = particles
                    .iter()
                    .map(|q| q.distance_squared(p))
                    .filter(|&d| d > 0.0)
                    .fold(f32::INFINITY, f32::min);
                nearest.is_finite().then(|| nearest.sqrt())
            })
            .collect()
    }

    /// Ball counts computed the slow way, for the same samples.
    fn brute_force_counts(particles: &[Vec3], max_samples: usize, radius: f32) -> Vec<[f32; 2]> {
        let (full, half) = (Ball::new(radius), Ball::new(radius / 2.0));
        let samples: Vec<Vec3> = stratified(particles, max_samples).collect();
        samples
            .par_iter()
            .filter(|p| p.is_finite())
            .map(|&p| {
                let mut found: Vec<(f32, Vec3)> = Vec::new();
                for &q in particles.iter().filter(|q| q.is_finite()) {
                    let d = q.distance_squared(p);
                    if d > 0.0 && d < full.outer && !found.iter().any(|e| e.1 == q) {
                        found.push((d, q));
                    }
                }
                found.iter().fold([1.0, 1.0], |[f, h], &(d, _)| {
                    [f + full.weight(d), h + half.weight(d)]
                })
            })
            .collect()
    }

    /// Equal up to rounding: the sums run in different orders.
    fn assert_counts_eq(counts: &[[f32; 2]], expected: &[[f32; 2]], context: &str) {
        assert_eq!(counts.len(), expected.len(), "{context}");
        for (c, e) in counts.iter().zip(expected) {
            for k in 0..2 {
                assert!(
                    (c[k] - e[k]).abs() <= 1e-4 * e[k],
                    "{context}: {c:?} vs {e:?}"
                );
            }
        }
    }

    fn uneven_cloud() -> Vec<Vec3> {
        // Blobs of very different densities, a sheet, a line, duplicates and far strays.
        let mut noise = Noise(12345);
        let mut particles = Vec::new();
        for (center, radius, count) in [
            (Vec3::ZERO, 0.1, 3000),
            (Vec3::new(2.0, 0.0, 0.0), 0.5, 500),
            (Vec3::new(0.0, 3.0, 1.0), 0.01, 800),
        ] {
            particles.extend((0..count).map(|_| center + noise.vec() * radius));
        }
        particles.extend((0..400).map(|_| Vec3::new(noise.next(), noise.next(), 0.0) - 3.0));
        particles.extend((0..100).map(|i| Vec3::new(5.0, i as f32 * 0.003, 5.0)));
        particles.extend_from_within(..50);
        particles.extend([Vec3::splat(40.0), Vec3::new(-30.0, 7.0, 0.0), Vec3::NAN]);
        particles
    }

    #[test]
    fn grid_queries_are_exact() {
        let particles = uneven_cloud();
        let expected = brute_force(&particles, usize::MAX);
        let auto = grid_for(&particles, LOAD).unwrap();
        let rough = grid_for(&particles, ROUGH_LOAD).unwrap();
        let finite = particles.iter().filter(|p| p.is_finite());
        let min = finite.clone().fold(Vec3::INFINITY, |a, &p| a.min(p));
        let max = finite.fold(Vec3::NEG_INFINITY, |a, &p| a.max(p));
        assert_eq!(nearest_distances(&auto, &particles, usize::MAX), expected);
        let radii = [0.004, 0.03, 0.4];
        let expected_counts: Vec<_> = radii
            .iter()
            .map(|&r| brute_force_counts(&particles, 1000, r))
            .collect();
        // Whatever the cell size and the table's: tiny cells force many shells and the full-scan
        // fallbacks, huge ones put everything in a few buckets.
        let grids: Vec<BucketGrid> = [1e-4, 3e-3, 0.05, 1.0, 100.0]
            .into_iter()
            .flat_map(|cell| {
                [LOAD, ROUGH_LOAD].map(|load| {
                    BucketGrid::new(&particles, particles.len() - 1, min, max - min, cell, load)
                })
            })
            .collect();
        for grid in grids.iter().chain([&auto, &rough]) {
            let (cell, buckets) = (grid.cell, grid.buckets());
            assert_eq!(
                nearest_distances(grid, &particles, usize::MAX),
                expected,
                "cell {cell}, {buckets} buckets"
            );
            for (&r, counts) in radii.iter().zip(&expected_counts) {
                assert_counts_eq(
                    &ball_counts(grid, &particles, 1000, r),
                    counts,
                    &format!("cell {cell}, {buckets} buckets, radius {r}"),
                );
            }
        }
        for samples in [1, 2, 7, 64, 1000] {
            assert_eq!(
                nearest_distances(&auto, &particles, samples),
                brute_force(&particles, samples),
                "{samples} samples"
            );
        }
        // The median, with searches cut short, is the full searches' median on every grid.
        for grid in grids.iter().chain([&auto, &rough]) {
            for samples in [1, 2, 7, 64, 1000] {
                assert_eq!(
                    median_nearest(grid, &particles, samples),
                    median(brute_force(&particles, samples)),
                    "cell {}, {} buckets, {samples} samples",
                    grid.cell,
                    grid.buckets()
                );
            }
        }
    }

    #[test]
    fn million_particle_lattice() {
        let particles = lattice([100, 100, 100], 0.005, 0.02);
        for samples in [10_000, 100_000, 1_000_000] {
            let start = Instant::now();
            let estimate = estimate_sampled(&particles, samples);
            eprintln!(
                "1 M lattice, {samples} samples: {estimate:?} in {:?}",
                start.elapsed()
            );
            assert_close(estimate, 0.005, 0.03);
        }
    }

    /// Positions from a binary little-endian PLY whose vertices start with float x y z and
    /// have `stride` bytes each; None when the file is absent.
    fn read_ply_positions(path: &str, stride: usize) -> Option<Vec<Vec3>> {
        let bytes = std::fs::read(path).ok()?;
        let marker = b"end_header\n";
        let header_end = bytes.windows(marker.len()).position(|w| w == marker)? + marker.len();
        let float =
            |record: &[u8], at: usize| f32::from_le_bytes(record[at..at + 4].try_into().unwrap());
        Some(
            bytes[header_end..]
                .chunks_exact(stride)
                .map(|r| Vec3::new(float(r, 0), float(r, 4), float(r, 8)))
                .collect(),
        )
    }

    /// Checks the grid's queries on a real frame against full scans, and the estimate against
    /// the simulator's spacing `r` (within 5%); prints the estimate with its timing. Skipped
    /// when the file is absent.
    fn real_frame(file: &str, stride: usize, count: usize, r: f32) {
        let Some(path) = crate::tests::common::shared_data(file) else {
            return;
        };
        let particles = read_ply_positions(path.to_str().unwrap(), stride).unwrap();
        assert_eq!(particles.len(), count);
        let grid = grid_for(&particles, LOAD).unwrap();
        assert_eq!(
            nearest_distances(&grid, &particles, 300),
            brute_force(&particles, 300)
        );
        assert_counts_eq(
            &ball_counts(&grid, &particles, 100, BALL * 0.8 * r),
            &brute_force_counts(&particles, 100, BALL * 0.8 * r),
            file,
        );
        for samples in [10_000, 100_000, usize::MAX] {
            let start = Instant::now();
            let estimate = estimate_sampled(&particles, samples);
            eprintln!(
                "{file}, {samples} samples: {estimate:?} = {:?} r in {:?}",
                estimate.map(|e| e / r),
                start.elapsed()
            );
            assert_close(estimate, r, 0.05);
        }
    }

    #[test]
    fn real_frames() {
        // The initial block: a lattice of spacing r.
        real_frame("cbd-small/frame_0001.ply", 28, 44_064, 0.014);
        // Settled, disordered fluid: nearest neighbours at 0.85 r and 0.78 r.
        real_frame("cbd-small/frame_0040.ply", 28, 44_064, 0.014);
        real_frame("cbd-large/frame_0023.ply", 12, 1_054_872, 0.005);
    }
}
