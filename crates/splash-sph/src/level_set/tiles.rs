//! The signs of a level set's tiles: the regions of the tree without leaves, each at
//! +background outside the surface and −background inside (what OpenVDB's `signedFloodFill`
//! sets). A tile holds no voxel within the band, so no surface, and a region of such tiles has
//! one sign; it is the sign of any voxel of a child next to it, which lies more than two
//! voxels from the surface on the same side. So each internal node's tiles are flooded from
//! their neighbouring children, the 16³ nodes (children: leaves) before the 32³ ones
//! (children: 16³ nodes), and the root's regions of 4096³ voxels last, in a box around its
//! nodes whose rim is outside (it lies beyond every surface).

use std::collections::VecDeque;

use glam::IVec3;
use rustc_hash::FxHashMap;

use super::STEPS;
use crate::io::{VdbNode, VdbTree, vdb_node_origin, vdb_slot};

/// Log2 of the edges, in voxels, of a leaf, a 16³ node and a 32³ node.
const LEAF: u32 = 3;
const NODE4: u32 = 7;
const NODE5: u32 = 12;

/// Sets the `outside` bits of every node's tiles and lists the root's inside tiles; the leaves'
/// `outside` bits must be set for every voxel.
pub(super) fn fill_signs(tree: &mut VdbTree) {
    let leaves: FxHashMap<[i32; 3], usize> = index(tree.leaves.iter().map(|l| l.origin));
    let outside_in_leaf = |v: IVec3| {
        let leaf = &tree.leaves[leaves[&vdb_node_origin(v.into(), LEAF)]];
        bit(&leaf.outside, vdb_slot(v.into(), 0, LEAF))
    };
    let filled: Vec<Vec<u64>> = tree
        .nodes4
        .iter()
        .map(|n| flood_node(n, NODE4, LEAF, &outside_in_leaf))
        .collect();
    for (node, outside) in tree.nodes4.iter_mut().zip(filled) {
        node.outside = outside;
    }
    let nodes4: FxHashMap<[i32; 3], usize> = index(tree.nodes4.iter().map(|n| n.origin));
    let outside_in_node4 = |v: IVec3| {
        let node = &tree.nodes4[nodes4[&vdb_node_origin(v.into(), NODE4)]];
        let s = vdb_slot(v.into(), LEAF, NODE4 - LEAF);
        if bit(&node.children, s) {
            outside_in_leaf(v)
        } else {
            bit(&node.outside, s)
        }
    };
    let filled: Vec<Vec<u64>> = tree
        .nodes5
        .iter()
        .map(|n| flood_node(n, NODE5, NODE4, &outside_in_node4))
        .collect();
    for (node, outside) in tree.nodes5.iter_mut().zip(filled) {
        node.outside = outside;
    }
    tree.inside_tiles = root_inside_tiles(tree, &nodes4);
}

/// The root's regions without a node that lie inside: flooded over the nodes' box grown by one
/// region, whose rim is outside.
fn root_inside_tiles(tree: &VdbTree, nodes4: &FxHashMap<[i32; 3], usize>) -> Vec<[i32; 3]> {
    let Some(first) = tree.nodes5.first() else {
        return Vec::new();
    };
    let leaves: FxHashMap<[i32; 3], usize> = index(tree.leaves.iter().map(|l| l.origin));
    let nodes5: FxHashMap<[i32; 3], usize> = index(tree.nodes5.iter().map(|n| n.origin));
    let outside_at = |v: IVec3| {
        let n5 = &tree.nodes5[nodes5[&vdb_node_origin(v.into(), NODE5)]];
        let s5 = vdb_slot(v.into(), NODE4, NODE5 - NODE4);
        if !bit(&n5.children, s5) {
            return bit(&n5.outside, s5);
        }
        let n4 = &tree.nodes4[nodes4[&vdb_node_origin(v.into(), NODE4)]];
        let s4 = vdb_slot(v.into(), LEAF, NODE4 - LEAF);
        if !bit(&n4.children, s4) {
            return bit(&n4.outside, s4);
        }
        let leaf = &tree.leaves[leaves[&vdb_node_origin(v.into(), LEAF)]];
        bit(&leaf.outside, vdb_slot(v.into(), 0, LEAF))
    };
    let (mut lo, mut hi) = (IVec3::from(first.origin), IVec3::from(first.origin));
    for n in &tree.nodes5 {
        lo = lo.min(IVec3::from(n.origin));
        hi = hi.max(IVec3::from(n.origin));
    }
    // In regions of 4096 voxels: the box and its rim.
    let (lo, hi) = ((lo >> NODE5) - 1, (hi >> NODE5) + 1);
    let dims = hi - lo + 1;
    let is_child = |c: IVec3| nodes5.contains_key(&((lo + c) << NODE5).to_array());
    let rim = |c: IVec3| c.min_element() == 0 || (dims - 1 - c).min_element() == 0;
    let signs = flood(lo << NODE5, dims, NODE5, is_child, rim, outside_at);
    let mut inside = Vec::new();
    for (i, s) in signs.iter().enumerate() {
        if *s == Some(false) {
            inside.push(((lo + cell_of(i, dims)) << NODE5).to_array());
        }
    }
    inside
}

/// The `outside` mask of the tiles of `node` (`log2` voxels a side, children `child_log2`).
fn flood_node(
    node: &VdbNode,
    log2: u32,
    child_log2: u32,
    outside_at: &impl Fn(IVec3) -> bool,
) -> Vec<u64> {
    let side = 1 << (log2 - child_log2);
    let dims = IVec3::splat(side);
    // Cells in x-major order are the node's slots (`InternalNode::coordToOffset`).
    let is_child = |c: IVec3| bit(&node.children, slot_of(c, side));
    let signs = flood(
        IVec3::from(node.origin),
        dims,
        child_log2,
        is_child,
        |_| false,
        outside_at,
    );
    let mut outside = vec![0u64; node.children.len()];
    for c in cells(dims) {
        // A node always has a child, and every tile region borders one: all are signed.
        if signs[cell_index(c, dims)].unwrap_or(true) {
            let s = slot_of(c, side);
            outside[s >> 6] |= 1 << (s & 63);
        }
    }
    outside
}

/// Breadth-first signs (true: outside) of the non-child cells of a box of `dims` cells of
/// `cell_log2` voxels from voxel `origin`: a cell on the `rim` is outside, one next to a child
/// has the sign of the child's voxel next to it, and the others that of a signed neighbour.
/// Children and cells that nothing reaches are None.
fn flood(
    origin: IVec3,
    dims: IVec3,
    cell_log2: u32,
    is_child: impl Fn(IVec3) -> bool,
    rim: impl Fn(IVec3) -> bool,
    outside_at: impl Fn(IVec3) -> bool,
) -> Vec<Option<bool>> {
    let mut signs: Vec<Option<bool>> = vec![None; (dims.x * dims.y * dims.z) as usize];
    let inside_box = |c: IVec3| c.cmpge(IVec3::ZERO).all() && c.cmplt(dims).all();
    let mut queue = VecDeque::new();
    for c in cells(dims) {
        if is_child(c) {
            continue;
        }
        let sign = if rim(c) {
            Some(true)
        } else {
            STEPS.iter().find_map(|&step| {
                let n = c + step;
                (inside_box(n) && is_child(n)).then(|| {
                    // The child's voxel nearest this cell's first one: on the face they share.
                    let first = origin + (c << cell_log2);
                    let child_lo = origin + (n << cell_log2);
                    let child_hi = child_lo + ((1 << cell_log2) - 1);
                    outside_at(first.clamp(child_lo, child_hi))
                })
            })
        };
        if sign.is_some() {
            signs[cell_index(c, dims)] = sign;
            queue.push_back(c);
        }
    }
    while let Some(c) = queue.pop_front() {
        let sign = signs[cell_index(c, dims)];
        for step in STEPS {
            let n = c + step;
            if inside_box(n) && !is_child(n) && signs[cell_index(n, dims)].is_none() {
                signs[cell_index(n, dims)] = sign;
                queue.push_back(n);
            }
        }
    }
    signs
}

fn cells(dims: IVec3) -> impl Iterator<Item = IVec3> {
    (0..dims.x).flat_map(move |x| {
        (0..dims.y).flat_map(move |y| (0..dims.z).map(move |z| IVec3::new(x, y, z)))
    })
}

fn cell_index(c: IVec3, dims: IVec3) -> usize {
    ((c.x * dims.y + c.y) * dims.z + c.z) as usize
}

fn cell_of(i: usize, dims: IVec3) -> IVec3 {
    let i = i as i32;
    IVec3::new(i / (dims.y * dims.z), (i / dims.z) % dims.y, i % dims.z)
}

fn slot_of(c: IVec3, side: i32) -> usize {
    ((c.x * side + c.y) * side + c.z) as usize
}

fn bit(mask: &[u64], n: usize) -> bool {
    mask[n >> 6] >> (n & 63) & 1 == 1
}

fn index(origins: impl Iterator<Item = [i32; 3]>) -> FxHashMap<[i32; 3], usize> {
    origins.enumerate().map(|(i, o)| (o, i)).collect()
}
