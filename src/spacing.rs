//! Estimates the particle spacing `r` (the equilibrium distance between SPH particles) when the
//! user gives neither `--spacing` nor `--particle-radius`.

use glam::Vec3;
use rayon::prelude::*;

/// Cells per axis stay below 2^20 + 1 so that a cell's coordinates pack into 21 bits each for
/// hashing, and shells stay bounded whatever the outliers.
const MAX_CELLS_PER_AXIS: f32 = (1 << 20) as f32;

/// Size of the strided subset that sizes the grid cells, and how many of its particles are
/// queried to do so.
const POOL: usize = 1 << 14;
const POOL_QUERIES: usize = 64;

/// Median nearest-neighbour distance over a deterministic sample of at most `max_samples`
/// particles (evenly strided through the array, so the same input gives the same answer). None
/// when fewer than 2 particles or all coincide.
///
/// Distances of exactly 0 are skipped: a particle coincident with the sample (the sample itself
/// or a duplicate) says nothing about the spacing. Particles with non-finite coordinates are
/// ignored. For an even number of samples the upper of the two middle values is returned.
///
/// On a lattice (a simulation's initial block) this is the spacing exactly; in a disordered,
/// settled SPH fluid nearest neighbours sit closer than `r` (0.85 r and 0.78 r on the two
/// SPlisHSPlasH frames in `shared/data`).
pub fn estimate_spacing(particles: &[Vec3], max_samples: usize) -> Option<f32> {
    median(Grid::build(particles)?.nearest_distances(particles, max_samples))
}

/// `count` items (at least one, at most all) evenly strided through `items`, first included.
fn strided<T: Copy>(items: &[T], count: usize) -> impl Iterator<Item = T> {
    let n = items.len();
    let count = count.max(1).min(n);
    (0..count).map(move |i| items[i * n / count])
}

fn median(mut values: Vec<f32>) -> Option<f32> {
    if values.is_empty() {
        return None;
    }
    let mid = values.len() / 2;
    Some(*values.select_nth_unstable_by(mid, f32::total_cmp).1)
}

/// Uniform grid over the bounding box, stored as a spatial hash: each cell maps to one of a
/// power-of-two number of buckets, and the particles are counting-sorted by bucket into one
/// array. A bucket may also hold particles of other cells; that only costs a few extra distance
/// checks, never correctness, and saves a hash map and a comparison sort.
struct Grid {
    min: Vec3,
    cell: f32,
    dims: [i32; 3],
    /// 64 minus log2 of the bucket count: the hash keeps the top bits.
    shift: u32,
    points: Vec<Vec3>,
    /// Bucket `b` holds `points[offsets[b]..offsets[b + 1]]`.
    offsets: Vec<u32>,
    occupied: usize,
}

impl Grid {
    /// A grid sized for nearest-neighbour queries on `particles`; None when fewer than two of
    /// them are finite or all of those coincide.
    fn build(particles: &[Vec3]) -> Option<Self> {
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
        // neighbours in a strided subset instead, scaled from its density to the full one.
        let pool: Vec<Vec3> = strided(particles, POOL).filter(|p| p.is_finite()).collect();
        let pool_grid = Grid::new(
            &pool,
            pool.len(),
            min,
            extent,
            (2.0 * spread(pool.len())).max(min_cell),
        );
        let cell = match median(pool_grid.nearest_distances(&pool, POOL_QUERIES)) {
            Some(d) => 2.0 * d * (pool.len() as f32 / finite as f32).powf(1.0 / dims as f32),
            None => 2.0 * spread(finite),
        };
        drop(pool_grid);
        Some(Grid::new(
            particles,
            finite,
            min,
            extent,
            cell.max(min_cell),
        ))
    }

    fn new(particles: &[Vec3], finite: usize, min: Vec3, extent: Vec3, cell: f32) -> Self {
        assert!(finite < u32::MAX as usize, "offsets are u32");
        // Half a bucket per particle: with ~8 particles per occupied cell collisions stay rare,
        // and the table stays small enough for the caches (random access dominates the build).
        let buckets = (finite / 2).next_power_of_two().max(2);
        let mut grid = Self {
            min,
            cell,
            dims: (extent / cell).to_array().map(|e| e as i32 + 1),
            shift: 64 - buckets.trailing_zeros(),
            points: vec![Vec3::ZERO; finite],
            offsets: vec![0; buckets + 1],
            occupied: 0,
        };
        let bucket_of: Vec<u32> = particles
            .par_iter()
            .map(|&p| {
                if p.is_finite() {
                    grid.bucket(grid.cell_of(p)) as u32
                } else {
                    u32::MAX
                }
            })
            .collect();
        // Counting sort: counts shifted by one, exclusive prefix sum, then scattering advances
        // each bucket's start to its end, which is where the next bucket starts.
        for &b in bucket_of.iter().filter(|&&b| b != u32::MAX) {
            grid.offsets[b as usize + 1] += 1;
        }
        let mut start = 0;
        for offset in &mut grid.offsets[1..] {
            grid.occupied += usize::from(*offset > 0);
            (*offset, start) = (start, start + *offset);
        }
        for (&b, &p) in bucket_of.iter().zip(particles) {
            if b != u32::MAX {
                let slot = &mut grid.offsets[b as usize + 1];
                grid.points[*slot as usize] = p;
                *slot += 1;
            }
        }
        grid
    }

    fn cell_of(&self, p: Vec3) -> [i32; 3] {
        let c = ((p - self.min) / self.cell).to_array();
        std::array::from_fn(|a| (c[a] as i32).clamp(0, self.dims[a] - 1))
    }

    /// Fibonacci hashing of the packed cell coordinates (21 bits each).
    fn bucket(&self, c: [i32; 3]) -> usize {
        let key = (c[0] as u64) << 42 | (c[1] as u64) << 21 | c[2] as u64;
        (key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> self.shift) as usize
    }

    /// Nearest non-zero distance from each of at most `max_samples` evenly strided particles.
    fn nearest_distances(&self, particles: &[Vec3], max_samples: usize) -> Vec<f32> {
        let samples: Vec<Vec3> = strided(particles, max_samples).collect();
        samples
            .par_iter()
            .filter(|p| p.is_finite())
            .filter_map(|&p| self.nearest(p).map(f32::sqrt))
            .collect()
    }

    /// Squared distance from `p` to the nearest particle not coincident with it, searching
    /// shells of cells at growing Chebyshev distance `k` around `p`'s cell. Anything beyond
    /// shell `k` is at least `k` cells away, so a candidate within `k * cell` is final.
    fn nearest(&self, p: Vec3) -> Option<f32> {
        let c = self.cell_of(p);
        let mut best = f32::INFINITY;
        let mut visited = 0;
        for k in 0.. {
            let lo: [i32; 3] = std::array::from_fn(|a| (c[a] - k).max(0));
            let hi: [i32; 3] = std::array::from_fn(|a| (c[a] + k).min(self.dims[a] - 1));
            for x in lo[0]..=hi[0] {
                for y in lo[1]..=hi[1] {
                    // Inside the shell's x/y faces only the two z layers at distance k are new.
                    let side = (x - c[0]).abs() == k || (y - c[1]).abs() == k;
                    let layers = if side {
                        (lo[2]..=hi[2]).step_by(1)
                    } else {
                        (c[2] - k..=c[2] + k).step_by(2 * k as usize)
                    };
                    for z in layers.filter(|z| (lo[2]..=hi[2]).contains(z)) {
                        visited += 1;
                        let b = self.bucket([x, y, z]);
                        let range = self.offsets[b] as usize..self.offsets[b + 1] as usize;
                        best = best.min(nearest_in(p, &self.points[range]));
                    }
                }
            }
            let reach = k as f32 * self.cell;
            if best <= reach * reach {
                break;
            }
            let covered = (0..3).all(|a| lo[a] == 0 && hi[a] == self.dims[a] - 1);
            if covered {
                break;
            }
            // An isolated particle (a far outlier) would need ever larger shells: once they
            // cost more than the occupied buckets, scanning everything is cheaper.
            if visited > self.occupied {
                best = nearest_in(p, &self.points);
                break;
            }
        }
        best.is_finite().then_some(best)
    }
}

impl Grid {
    /// Weighted count of the distinct positions within `outer` of each of at most
    /// `max_samples` strided particles, the sample itself included: weight 1 within `inner`,
    /// falling linearly in squared distance to 0 at `outer`.
    fn ball_counts(
        &self,
        particles: &[Vec3],
        max_samples: usize,
        inner: f32,
        outer: f32,
    ) -> Vec<f32> {
        let samples: Vec<Vec3> = strided(particles, max_samples).collect();
        let (a2, b2) = (inner * inner, outer * outer);
        samples
            .par_iter()
            .filter(|p| p.is_finite())
            .map_init(
                || (Vec::new(), Vec::new()),
                |(buckets, found): &mut (Vec<usize>, Vec<(Vec3, f32)>), &p| {
                    let lo = self.cell_of(p - outer);
                    let hi = self.cell_of(p + outer);
                    let cells: usize = (0..3).map(|a| (hi[a] - lo[a] + 1) as usize).product();
                    buckets.clear();
                    if cells > self.occupied {
                        buckets.extend(0..self.offsets.len() - 1);
                    } else {
                        for x in lo[0]..=hi[0] {
                            for y in lo[1]..=hi[1] {
                                for z in lo[2]..=hi[2] {
                                    buckets.push(self.bucket([x, y, z]));
                                }
                            }
                        }
                        buckets.sort_unstable();
                        buckets.dedup();
                    }
                    found.clear();
                    for &b in buckets.iter() {
                        let range = self.offsets[b] as usize..self.offsets[b + 1] as usize;
                        for &q in &self.points[range] {
                            let d = q.distance_squared(p);
                            if d > 0.0 && d < b2 {
                                found.push((q, d));
                            }
                        }
                    }
                    found.sort_unstable_by(|x, y| {
                        let (x, y) = (x.0.to_array(), y.0.to_array());
                        x[0].total_cmp(&y[0])
                            .then(x[1].total_cmp(&y[1]))
                            .then(x[2].total_cmp(&y[2]))
                    });
                    found.dedup_by(|x, y| x.0 == y.0);
                    1.0 + found
                        .iter()
                        .map(|&(_, d)| {
                            if b2 > a2 {
                                ((b2 - d) / (b2 - a2)).min(1.0)
                            } else {
                                1.0
                            }
                        })
                        .sum::<f32>()
                },
            )
            .collect()
    }
}

/// Volume of the weight of `ball_counts`.
fn ball_volume(inner: f32, outer: f32) -> f32 {
    let (a, b) = (f64::from(inner), f64::from(outer));
    let ramp = if b > a {
        (b * b * (b.powi(3) - a.powi(3)) / 3.0 - (b.powi(5) - a.powi(5)) / 5.0) / (b * b - a * a)
    } else {
        0.0
    };
    (4.0 * std::f64::consts::PI * (a.powi(3) / 3.0 + ramp)) as f32
}

/// Smallest non-zero squared distance from `p` to `points`.
fn nearest_in(p: Vec3, points: &[Vec3]) -> f32 {
    points
        .iter()
        .map(|q| q.distance_squared(p))
        .filter(|&d| d > 0.0)
        .fold(f32::INFINITY, f32::min)
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

    #[test]
    fn jittered_lattice() {
        let particles = lattice([30, 25, 20], 0.014, 0.02);
        assert_close(estimate_spacing(&particles, 10_000), 0.014, 0.03);
        // Deterministic: same input, same answer.
        assert_eq!(
            estimate_spacing(&particles, 1000),
            estimate_spacing(&particles, 1000)
        );
    }

    #[test]
    fn lattice_far_off_origin() {
        let particles: Vec<Vec3> = lattice([20, 20, 20], 0.014, 0.02)
            .into_iter()
            .map(|p| p + Vec3::new(100.0, -50.0, 20.0))
            .collect();
        assert_close(estimate_spacing(&particles, 10_000), 0.014, 0.03);
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
        assert_close(estimate_spacing(&particles, usize::MAX), 0.014, 0.03);
        assert_close(estimate_spacing(&particles, 500), 0.014, 0.03);
    }

    #[test]
    fn fluid_in_a_corner_of_a_big_box() {
        // A dense block plus a sparse spray over a box 50 times wider.
        let mut particles = lattice([20, 20, 20], 0.01, 0.02);
        let mut noise = Noise(7);
        particles.extend((0..200).map(|_| (noise.vec() + 1.0) * 5.0));
        assert_close(estimate_spacing(&particles, 10_000), 0.01, 0.03);
    }

    #[test]
    fn flat_sheet_and_line() {
        let sheet: Vec<Vec3> = lattice([60, 50, 1], 0.014, 0.02)
            .into_iter()
            .map(|p| Vec3::new(p.x, p.y, 0.3))
            .collect();
        assert_close(estimate_spacing(&sheet, 10_000), 0.014, 0.03);
        let line: Vec<Vec3> = (0..1000).map(|i| Vec3::X * (i as f32 * 0.02)).collect();
        assert_close(estimate_spacing(&line, 10_000), 0.02, 1e-4);
    }

    #[test]
    fn samples_are_evenly_strided() {
        let items: Vec<usize> = (0..10).collect();
        let pick = |count| strided(&items, count).collect::<Vec<_>>();
        assert_eq!(pick(3), [0, 3, 6]);
        assert_eq!(pick(4), [0, 2, 5, 7]);
        assert_eq!(pick(0), [0]);
        assert_eq!(pick(usize::MAX), items);
    }

    #[test]
    fn tiny_inputs() {
        assert_eq!(estimate_spacing(&[], 100), None);
        assert_eq!(estimate_spacing(&[Vec3::ONE], 100), None);
        assert_eq!(estimate_spacing(&[Vec3::ONE; 5], 100), None);
        let two = [Vec3::new(1.0, 2.0, 3.0), Vec3::new(1.0, 2.0, 3.5)];
        assert_eq!(estimate_spacing(&two, 100), Some(0.5));
        assert_eq!(estimate_spacing(&two, 0), Some(0.5));
        let with_nan = [two[0], Vec3::NAN, two[1]];
        assert_eq!(estimate_spacing(&with_nan, 100), Some(0.5));
    }

    #[test]
    fn duplicates_are_skipped() {
        // Every particle doubled: the zero distances to the twins don't count.
        let particles: Vec<Vec3> = lattice([10, 10, 10], 0.05, 0.0)
            .into_iter()
            .flat_map(|p| [p, p])
            .collect();
        assert_close(estimate_spacing(&particles, 10_000), 0.05, 1e-5);
    }

    /// Nearest non-zero distances computed the slow way, for the same strided samples.
    fn brute_force(particles: &[Vec3], max_samples: usize) -> Vec<f32> {
        let samples: Vec<Vec3> = strided(particles, max_samples).collect();
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
    fn grid_finds_exact_nearest_neighbours() {
        let particles = uneven_cloud();
        let expected = brute_force(&particles, usize::MAX);
        let auto = Grid::build(&particles).unwrap();
        let finite = particles.iter().filter(|p| p.is_finite());
        let min = finite.clone().fold(Vec3::INFINITY, |a, &p| a.min(p));
        let max = finite.fold(Vec3::NEG_INFINITY, |a, &p| a.max(p));
        assert_eq!(auto.nearest_distances(&particles, usize::MAX), expected);
        // Whatever the cell size: tiny cells force many shells and the full-scan fallback, huge
        // ones put everything in a few buckets.
        for cell in [1e-4, 3e-3, 0.05, 1.0, 100.0] {
            let grid = Grid::new(&particles, particles.len() - 1, min, max - min, cell);
            assert_eq!(
                grid.nearest_distances(&particles, usize::MAX),
                expected,
                "cell {cell}"
            );
        }
        for samples in [1, 2, 7, 64, 1000] {
            assert_eq!(
                auto.nearest_distances(&particles, samples),
                brute_force(&particles, samples),
                "{samples} samples"
            );
        }
    }

    #[test]
    fn million_particle_lattice() {
        let particles = lattice([100, 100, 100], 0.005, 0.02);
        for samples in [10_000, 100_000, 1_000_000] {
            let start = Instant::now();
            let estimate = estimate_spacing(&particles, samples);
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

    /// Checks the estimate on a real frame against a full scan and prints it with its timing;
    /// returns it for comparison with the simulator's spacing, None when the file is absent.
    fn real_frame(file: &str, stride: usize, count: usize) -> Option<f32> {
        let path = format!("{}/../shared/data/{file}", env!("CARGO_MANIFEST_DIR"));
        let Some(particles) = read_ply_positions(&path, stride) else {
            eprintln!("{path} not found, skipped");
            return None;
        };
        assert_eq!(particles.len(), count);
        assert_eq!(
            Grid::build(&particles)
                .unwrap()
                .nearest_distances(&particles, 300),
            brute_force(&particles, 300)
        );
        let mut estimate = None;
        for samples in [10_000, 100_000, usize::MAX] {
            let start = Instant::now();
            estimate = estimate_spacing(&particles, samples);
            eprintln!(
                "{file}, {samples} samples: {estimate:?} in {:?}",
                start.elapsed()
            );
        }
        estimate
    }

    #[test]
    fn real_frames() {
        // The initial block is a lattice of spacing 0.014.
        if let Some(e) = real_frame("cbd-small/frame_0001.ply", 28, 44_064) {
            assert_close(Some(e), 0.014, 0.01);
        }
        // Settled, disordered fluid: nearest neighbours well inside r (see the doc comment).
        if let Some(e) = real_frame("cbd-small/frame_0040.ply", 28, 44_064) {
            assert!((0.80..0.90).contains(&(e / 0.014)), "{e}");
        }
        if let Some(e) = real_frame("cbd-large/frame_0023.ply", 12, 1_054_872) {
            assert!((0.74..0.82).contains(&(e / 0.005)), "{e}");
        }
    }

    fn percentile(mut v: Vec<f32>, q: f32) -> f32 {
        let i = ((v.len() - 1) as f32 * q) as usize;
        *v.select_nth_unstable_by(i, f32::total_cmp).1
    }

    fn explore(name: &str, particles: &[Vec3], r: f32) {
        let grid = Grid::build(particles).unwrap();
        let d = median(grid.nearest_distances(particles, 10_000)).unwrap();
        eprintln!("{name}: n {} d/r {:.3}", particles.len(), d / r);
        for m in [2.0f32, 2.5, 3.0, 3.08, 3.5, 4.0] {
            for ramp in [0.0f32, 0.2, 0.4] {
                let (inner, outer) = (m * d * (1.0 - ramp / 2.0), m * d * (1.0 + ramp / 2.0));
                let v = ball_volume(inner, outer);
                let counts = grid.ball_counts(particles, 10_000, inner, outer);
                let s: Vec<f32> = counts.iter().map(|c| (v / c).cbrt() / r).collect();
                eprintln!(
                    "  m {m} ramp {ramp}: p10 {:.3} p25 {:.3} p50 {:.3}  count p75 {:.1} p50 {:.1}",
                    percentile(s.clone(), 0.1),
                    percentile(s.clone(), 0.25),
                    percentile(s.clone(), 0.5),
                    percentile(counts.clone(), 0.75),
                    percentile(counts.clone(), 0.5),
                );
            }
        }
    }

    #[test]
    #[ignore]
    fn exploration() {
        let dir = format!("{}/../shared/data", env!("CARGO_MANIFEST_DIR"));
        let frames = [
            ("cbd-small/frame_0001.ply", 28, 0.014),
            ("cbd-small/frame_0040.ply", 28, 0.014),
            ("cbd-small/frame_0019.ply", 28, 0.014),
            ("cbd-small/frame_0061.ply", 28, 0.014),
            ("cbd-large/frame_0023.ply", 12, 0.005),
        ];
        for (f, stride, r) in frames {
            if let Some(p) = read_ply_positions(&format!("{dir}/{f}"), stride) {
                explore(f, &p, r);
            }
        }
        explore("lattice 0", &lattice([30, 30, 30], 1.0, 0.0), 1.0);
        explore("lattice .02", &lattice([30, 30, 30], 1.0, 0.02), 1.0);
        explore("lattice .1", &lattice([30, 30, 30], 1.0, 0.1), 1.0);
        explore("lattice 10^3", &lattice([10, 10, 10], 1.0, 0.02), 1.0);
        let mut noise = Noise(3);
        let poisson: Vec<Vec3> = (0..100_000).map(|_| noise.vec() * 23.2).collect();
        explore("poisson", &poisson, 1.0);
        let sheet: Vec<Vec3> = lattice([100, 100, 1], 1.0, 0.02)
            .into_iter()
            .map(|p| Vec3::new(p.x, p.y, 0.0))
            .collect();
        explore("sheet", &sheet, 1.0);
        explore("2 layers", &lattice([100, 100, 2], 1.0, 0.02), 1.0);
        explore("4 layers", &lattice([100, 100, 4], 1.0, 0.02), 1.0);
    }
}
