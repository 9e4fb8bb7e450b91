//! The point-insert, 3D-lookup particle cache of the baselines in Rosenberg & Birdwell 2008,
//! Sec. 6–7 (as Wyvill et al. 1986 and Müller et al. 2003 use it): each particle is inserted
//! into the coarse cell of size R_c that holds it; a lookup scans the 3×3×3 cells around a
//! corner and culls by distance. The cells live in an array over a block (approach 2) or in a
//! hash map (approach 3).

use glam::{DVec3, IVec3};
use rustc_hash::FxHashMap;

use super::hash_bytes;

/// Where a coarse cell's particles are.
pub trait Cells {
    /// The particles of cell `k`, in increasing index.
    fn get(&self, k: IVec3) -> &[u32];
    fn heap_bytes(&self) -> usize;
}

/// The cells of a box in one array: per cell a range of `items`.
pub struct ArrayCells {
    lo: IVec3,
    dims: IVec3,
    start: Vec<u32>,
    items: Vec<u32>,
}

impl ArrayCells {
    fn build(keys: &[IVec3]) -> ArrayCells {
        let lo = keys.iter().copied().reduce(IVec3::min).unwrap_or_default();
        let hi = keys.iter().copied().reduce(IVec3::max).unwrap_or_default();
        let dims = hi - lo + 1;
        let at = |k: IVec3| {
            let d = k - lo;
            ((d.z * dims.y + d.y) * dims.x + d.x) as usize
        };
        let mut start = vec![0u32; dims.element_product() as usize + 1];
        for &k in keys {
            start[at(k) + 1] += 1;
        }
        for i in 1..start.len() {
            start[i] += start[i - 1];
        }
        let mut fill = start.clone();
        let mut items = vec![0u32; keys.len()];
        for (i, &k) in keys.iter().enumerate() {
            items[fill[at(k)] as usize] = i as u32;
            fill[at(k)] += 1;
        }
        ArrayCells {
            lo,
            dims,
            start,
            items,
        }
    }
}

impl Cells for ArrayCells {
    fn get(&self, k: IVec3) -> &[u32] {
        let d = k - self.lo;
        if d.cmplt(IVec3::ZERO).any() || d.cmpge(self.dims).any() {
            return &[];
        }
        let i = ((d.z * self.dims.y + d.y) * self.dims.x + d.x) as usize;
        &self.items[self.start[i] as usize..self.start[i + 1] as usize]
    }

    fn heap_bytes(&self) -> usize {
        (self.start.capacity() + self.items.capacity()) * size_of::<u32>()
    }
}

/// The non-empty cells in a hash map, unbounded: per cell a range of `items`.
pub struct HashedCells {
    ranges: FxHashMap<IVec3, (u32, u32)>,
    items: Vec<u32>,
}

impl HashedCells {
    fn build(keys: &[IVec3]) -> HashedCells {
        let mut ranges: FxHashMap<IVec3, (u32, u32)> = FxHashMap::default();
        for &k in keys {
            ranges.entry(k).or_default().1 += 1;
        }
        let mut total = 0;
        for r in ranges.values_mut() {
            let count = r.1;
            *r = (total, total);
            total += count;
        }
        let mut items = vec![0u32; keys.len()];
        for (i, &k) in keys.iter().enumerate() {
            let r = ranges.get_mut(&k).expect("counted");
            items[r.1 as usize] = i as u32;
            r.1 += 1;
        }
        HashedCells { ranges, items }
    }
}

impl Cells for HashedCells {
    fn get(&self, k: IVec3) -> &[u32] {
        self.ranges
            .get(&k)
            .map_or(&[], |&(a, b)| &self.items[a as usize..b as usize])
    }

    fn heap_bytes(&self) -> usize {
        hash_bytes(&self.ranges) + self.items.capacity() * size_of::<u32>()
    }
}

/// The particles, by height, in cube units, with their coarse cells.
pub struct ParticleGrid<C> {
    cells: C,
    /// Cube units per coarse cell: the largest reach, widened a hair so that a particle at
    /// exactly its reach of a corner lies within one cell of it whatever the rounding.
    size: f64,
    /// Positions in cube units, computed as the slices engine's lookup cache computes them.
    q: Vec<DVec3>,
    /// Each particle's squared reach in cube units; empty when all reach `h2_all`.
    h2: Vec<f64>,
    h2_all: f64,
}

impl<C: Cells> ParticleGrid<C> {
    fn new(
        q: Vec<DVec3>,
        reach: &dyn Fn(usize) -> f64,
        same_reach: bool,
        cells: impl Fn(&[IVec3]) -> C,
    ) -> Self {
        let max = (0..q.len()).map(reach).fold(0.0, f64::max);
        let size = max * (1.0 + 1e-6);
        let keys: Vec<IVec3> = q.iter().map(|p| (*p / size).floor().as_ivec3()).collect();
        let h2 = if same_reach {
            Vec::new()
        } else {
            (0..q.len()).map(|i| reach(i).powi(2)).collect()
        };
        ParticleGrid {
            cells: cells(&keys),
            size,
            q,
            h2,
            h2_all: max.powi(2),
        }
    }

    /// The particles within reach of corner `c` (cube units), into `out` by height: the order
    /// in which the slices engine's lookup returns them, so that the field sums the same
    /// numbers in the same order and every approach gets the same value to the bit. The three
    /// layers of cells come in height order; within one, the particles are sorted.
    pub fn within_reach(&self, c: IVec3, out: &mut Vec<u32>) {
        out.clear();
        let p = c.as_dvec3();
        let k = (p / self.size).floor().as_ivec3();
        for dz in -1..=1 {
            let layer = out.len();
            for dy in -1..=1 {
                for dx in -1..=1 {
                    for &i in self.cells.get(k + IVec3::new(dx, dy, dz)) {
                        let h2 = if self.h2.is_empty() {
                            self.h2_all
                        } else {
                            self.h2[i as usize]
                        };
                        if (self.q[i as usize] - p).length_squared() <= h2 {
                            out.push(i);
                        }
                    }
                }
            }
            out[layer..].sort_unstable();
        }
    }

    /// Bytes held: the paper's "cache memory" (cells and positions).
    pub fn heap_bytes(&self) -> usize {
        self.cells.heap_bytes()
            + self.q.capacity() * size_of::<DVec3>()
            + self.h2.capacity() * size_of::<f64>()
    }
}

impl ParticleGrid<ArrayCells> {
    /// The grid of a block's particles (`q`, cube units, by height), each reaching `reach(i)`
    /// cubes (`same_reach`: all the same).
    pub fn array(q: Vec<DVec3>, reach: &dyn Fn(usize) -> f64, same_reach: bool) -> Self {
        Self::new(q, reach, same_reach, ArrayCells::build)
    }
}

impl ParticleGrid<HashedCells> {
    /// [`ParticleGrid::array`] in a hash map.
    pub fn hashed(q: Vec<DVec3>, reach: &dyn Fn(usize) -> f64, same_reach: bool) -> Self {
        Self::new(q, reach, same_reach, HashedCells::build)
    }
}
