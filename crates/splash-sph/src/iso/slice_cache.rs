//! The slice cache (Sec. III-B): interpolant samples at grid nodes, kept for the last few z
//! slices only, since the surface is followed roughly in z order; a node asked for again after
//! its slice was dropped is evaluated again (a miss).

use std::collections::BTreeMap;

use glam::IVec3;
use rustc_hash::FxHashMap;

/// A and Σ V W at a node.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Node {
    pub value: f64,
    pub weight: f64,
}

pub(crate) struct SliceCache {
    slices: BTreeMap<i32, FxHashMap<(i32, i32), Node>>,
    keep: i32,
    /// Nodes asked for.
    pub lookups: u64,
    /// Nodes evaluated (the rest were hits).
    pub evaluations: u64,
    /// Most nodes held at once.
    pub peak_nodes: usize,
}

impl SliceCache {
    pub fn new(keep: u32) -> SliceCache {
        SliceCache {
            slices: BTreeMap::new(),
            keep: keep as i32,
            lookups: 0,
            evaluations: 0,
            peak_nodes: 0,
        }
    }

    /// Keeps the `keep` slices up to `top` (the upper node slice of the cells now processed).
    pub fn retain_up_to(&mut self, top: i32) {
        let low = top - self.keep + 1;
        self.slices.retain(|&z, _| z >= low && z <= top);
    }

    pub fn get(&self, n: IVec3) -> Option<Node> {
        self.slices.get(&n.z)?.get(&(n.x, n.y)).copied()
    }

    pub fn insert(&mut self, n: IVec3, node: Node) {
        self.slices.entry(n.z).or_default().insert((n.x, n.y), node);
    }

    /// Records one batch: `lookups` asked, `evaluated` computed.
    pub fn count(&mut self, lookups: usize, evaluated: usize) {
        self.lookups += lookups as u64;
        self.evaluations += evaluated as u64;
        let held = self.slices.values().map(FxHashMap::len).sum();
        self.peak_nodes = self.peak_nodes.max(held);
    }

    /// Share of lookups answered from the cache.
    pub fn hit_ratio(&self) -> f64 {
        if self.lookups == 0 {
            0.0
        } else {
            1.0 - self.evaluations as f64 / self.lookups as f64
        }
    }
}
