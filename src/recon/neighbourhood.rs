//! Particles gathered once around a small region and reused by every query point in it: the
//! "neighbour lists reused across nearby vertices" that keep the hot loops branch-free.

use glam::Vec3;

use super::handler_array::HandlerArray;

/// Width of the lane-parallel accumulators; the gathered arrays are padded to a multiple of it.
pub const LANES: usize = 8;

/// Padding coordinate: far outside every kernel, yet its square stays finite in f32, so that
/// `0 * d²` of a padded lane is 0 rather than NaN.
const FAR: f32 = 1.0e15;

/// Particle positions relative to an anchor point, as three coordinate arrays.
#[derive(Default)]
pub struct Neighbourhood {
    pub anchor: Vec3,
    pub x: Vec<f32>,
    pub y: Vec<f32>,
    pub z: Vec<f32>,
}

impl Neighbourhood {
    /// Gathers every particle within `radius` of the box `[lo, hi]`, relative to `lo`.
    pub fn gather_box(&mut self, handlers: &HandlerArray, lo: Vec3, hi: Vec3, radius: f32) {
        self.clear(lo);
        let r2 = radius * radius;
        handlers.for_each_in_box(lo - radius, hi + radius, |cell| {
            let start = self.x.len();
            self.x.resize(start + cell.len(), 0.0);
            self.y.resize(start + cell.len(), 0.0);
            self.z.resize(start + cell.len(), 0.0);
            let mut n = start;
            for &p in cell {
                let q = p - lo;
                (self.x[n], self.y[n], self.z[n]) = (q.x, q.y, q.z);
                n += usize::from((p - p.clamp(lo, hi)).length_squared() <= r2);
            }
            self.truncate(n);
        });
        self.pad();
    }

    /// Keeps from `from` the particles within `radius` of the box `[lo, hi]`, relative to `lo`.
    pub fn filter_box(&mut self, from: &Neighbourhood, lo: Vec3, hi: Vec3, radius: f32) {
        self.clear(lo);
        let r2 = radius * radius;
        let shift = from.anchor - lo;
        let (blo, bhi) = (Vec3::ZERO, hi - lo);
        let len = from.x.len();
        self.x.resize(len, 0.0);
        self.y.resize(len, 0.0);
        self.z.resize(len, 0.0);
        // Branch-free compaction: write every particle, advance only past the kept ones.
        let mut n = 0;
        for i in 0..len {
            let p = Vec3::new(from.x[i], from.y[i], from.z[i]) + shift;
            (self.x[n], self.y[n], self.z[n]) = (p.x, p.y, p.z);
            n += usize::from((p - p.clamp(blo, bhi)).length_squared() <= r2);
        }
        self.truncate(n);
        self.pad();
    }

    /// Holds exactly `points`, relative to `anchor`.
    pub fn set(&mut self, anchor: Vec3, points: &[Vec3]) {
        self.clear(anchor);
        for &p in points {
            self.push(p - anchor);
        }
        self.pad();
    }

    fn clear(&mut self, anchor: Vec3) {
        self.anchor = anchor;
        self.x.clear();
        self.y.clear();
        self.z.clear();
    }

    fn truncate(&mut self, n: usize) {
        self.x.truncate(n);
        self.y.truncate(n);
        self.z.truncate(n);
    }

    fn push(&mut self, p: Vec3) {
        self.x.push(p.x);
        self.y.push(p.y);
        self.z.push(p.z);
    }

    fn pad(&mut self) {
        while !self.x.len().is_multiple_of(LANES) {
            self.push(Vec3::splat(FAR));
        }
    }

    pub fn len(&self) -> usize {
        self.x.len()
    }

    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }
}
