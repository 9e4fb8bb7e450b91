//! A uniform grid over a bounding box stored as a spatial hash, for nearest-neighbour queries
//! and ball counts over scattered points (the spacing estimate's): counting-sorted buckets in
//! one array, no hash map.

use glam::Vec3;

use super::counting_sort::sort_by_bucket;

/// Uniform grid over the bounding box, stored as a spatial hash: each cell maps to one of a
/// power-of-two number of buckets, and the particles are counting-sorted by bucket into one
/// array. A bucket may also hold particles of other cells; that only costs a few extra distance
/// checks, never correctness, and saves a hash map and a comparison sort.
pub(crate) struct BucketGrid {
    min: Vec3,
    pub cell: f32,
    dims: [i32; 3],
    /// 64 minus log2 of the bucket count: the hash keeps the top bits.
    shift: u32,
    points: Vec<Vec3>,
    /// Bucket `b` holds `points[offsets[b]..offsets[b + 1]]`.
    offsets: Vec<u32>,
    /// Non-empty buckets.
    pub occupied: usize,
}

impl BucketGrid {
    /// The grid of the finite ones of `particles` (`finite` of them) in the box from `min`
    /// spanning `extent`, with cells of `cell` and about `load` particles per bucket: 2 keeps
    /// collisions rare (~8 particles per occupied cell) for many queries, more builds faster
    /// (random writes into a table that fits the caches) where the queries are few.
    pub fn new(
        particles: &[Vec3],
        finite: usize,
        min: Vec3,
        extent: Vec3,
        cell: f32,
        load: usize,
    ) -> Self {
        assert!(finite < u32::MAX as usize, "offsets are u32");
        let buckets = (finite / load.max(1)).next_power_of_two().max(8);
        let mut grid = Self {
            min,
            cell,
            dims: (extent / cell).to_array().map(|e| e as i32 + 1),
            shift: 64 - buckets.trailing_zeros(),
            points: Vec::new(),
            offsets: Vec::new(),
            occupied: 0,
        };
        let place = |_, &p: &Vec3| p.is_finite().then(|| (grid.bucket(grid.cell_of(p)), p));
        // SAFETY: `place` is a function of its arguments.
        let (points, offsets) = unsafe { sort_by_bucket(particles, buckets, place) };
        debug_assert_eq!(points.len(), finite);
        grid.occupied = offsets.windows(2).filter(|w| w[0] < w[1]).count();
        (grid.points, grid.offsets) = (points, offsets);
        grid
    }

    pub fn cell_of(&self, p: Vec3) -> [i32; 3] {
        let c = ((p - self.min) / self.cell).to_array();
        std::array::from_fn(|a| (c[a] as i32).clamp(0, self.dims[a] - 1))
    }

    /// Fibonacci hashing of the packed cell coordinates (21 bits each), with z in groups of 4
    /// cells that take 4 consecutive buckets: queries scan columns of cells along z, and read
    /// memory mostly in sequence.
    pub fn bucket(&self, c: [i32; 3]) -> usize {
        let key = (c[0] as u64) << 42 | (c[1] as u64) << 21 | (c[2] >> 2) as u64;
        let group = key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> (self.shift + 2);
        (group << 2 | (c[2] & 3) as u64) as usize
    }

    /// Buckets, numbered from 0.
    pub fn buckets(&self) -> usize {
        self.offsets.len() - 1
    }

    /// The points of bucket `b` (of its cell, and possibly of others).
    pub fn bucket_points(&self, b: usize) -> &[Vec3] {
        &self.points[self.offsets[b] as usize..self.offsets[b + 1] as usize]
    }

    /// Squared distance from `p` to the nearest particle not coincident with it, searching
    /// shells of cells at growing Chebyshev distance `k` around `p`'s cell. Anything beyond
    /// shell `k` is at least `k` cells away, so a candidate within `k * cell` is final.
    pub fn nearest(&self, p: Vec3) -> Option<f32> {
        match self.nearest_within(p, i32::MAX) {
            Nearest::Found(d) => Some(d),
            Nearest::None | Nearest::AtLeast(_) => None,
        }
    }

    /// [`BucketGrid::nearest`], giving up after shell `shells`: an isolated particle (spray,
    /// far outliers) then costs a few shells, and the caller learns only a lower bound.
    pub fn nearest_within(&self, p: Vec3, shells: i32) -> Nearest {
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
                        best = best.min(nearest_in(p, self.bucket_points(b)));
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
            if k >= shells {
                // Whatever lies beyond shell k is at least k cells away.
                return Nearest::AtLeast(best.min(reach * reach));
            }
            // An isolated particle (a far outlier) would need ever larger shells: once they
            // cost more than the occupied buckets, scanning everything is cheaper.
            if visited > self.occupied {
                best = nearest_in(p, &self.points);
                break;
            }
        }
        if best.is_finite() {
            Nearest::Found(best)
        } else {
            Nearest::None
        }
    }
}

/// What [`BucketGrid::nearest_within`] found: the squared distance, that there is no other
/// particle, or a lower bound on the squared distance when it gave up.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Nearest {
    Found(f32),
    None,
    AtLeast(f32),
}

/// Smallest non-zero squared distance from `p` to `points`.
fn nearest_in(p: Vec3, points: &[Vec3]) -> f32 {
    points
        .iter()
        .map(|q| q.distance_squared(p))
        .filter(|&d| d > 0.0)
        .fold(f32::INFINITY, f32::min)
}
