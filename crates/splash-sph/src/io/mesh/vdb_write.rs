//! OpenVDB output (`.vdb`): sparse voxel grids in the file format that OpenVDB 10–12's
//! `io::File::write` produces (file version 224), which Blender, Houdini and OpenVDB's own
//! tools read. No maintained Rust crate writes VDB, so this module writes it from the format's
//! definition in OpenVDB's sources; each section below is named as OpenVDB names it.
//!
//! The file (`io/Archive.cc`, `Archive::writeHeader` and `Archive::write`): magic, file and
//! library versions, a has-grid-offsets flag, a UUID, the file's metadata (none), the grid
//! count, then per grid its descriptor (`GridDescriptor::writeHeader`: name, type, instance
//! parent; then its grid, block and end offsets) and the grid (`Archive::writeGrid`):
//! compression flags, metadata (`MetaMap::writeMeta`), transform (`Transform::write`, a
//! `UniformScaleTranslateMap`), topology (`Tree::writeTopology`: root, `InternalNode` 5 and 4,
//! leaf value masks) and buffers (`LeafNode::writeBuffers`). Values are written with
//! `COMPRESS_ACTIVE_MASK` (`io/Compression.h`, `writeCompressedValues`), as OpenVDB itself
//! writes level sets: each node's active values only, after a byte saying what its inactive
//! values are (all +background, all −background, or a mask choosing between the two). The
//! offsets are known before each grid is written (the sections are sized by writing them to a
//! counter), so the file is written in one pass to any stream.
//!
//! Every grid of a file shares one tree of active voxels ([`VdbTree`], 8³ leaves under nodes
//! of 16³ and 32³ children, OpenVDB's `Tree_*_5_4_3`) and one voxel size; each has its own
//! values, one per active voxel in the tree's order.

use std::hash::Hasher;
use std::io::{self, Write};

use glam::Vec3;
use rustc_hash::FxHasher;

use super::failure::invalid_input;

/// `OPENVDB_MAGIC`, written as an `int64`.
const MAGIC: i64 = 0x5644_4220;
/// `OPENVDB_FILE_VERSION_MULTIPASS_IO`, the version OpenVDB 10 and 11 write (12 reads it too).
const FILE_VERSION: u32 = 224;
/// The library version the file claims (OpenVDB 10.0, the oldest that writes version 224).
const LIBRARY_VERSION: [u32; 2] = [10, 0];
/// `io::COMPRESS_ACTIVE_MASK`.
const COMPRESS_ACTIVE_MASK: u32 = 0x2;
/// Per-node metadata bytes of `writeCompressedValues`.
const NO_MASK_OR_INACTIVE_VALS: u8 = 0;
const NO_MASK_AND_MINUS_BG: u8 = 1;
const MASK_AND_NO_INACTIVE_VALS: u8 = 3;

/// Log2 of the edges of the two internal levels' nodes, in children (`InternalNode<_, 4>`,
/// `InternalNode<_, 5>`), and of their edges in voxels.
const LOG2_NODE4: u32 = 4;
const LOG2_NODE5: u32 = 5;
const VOXELS_LOG2_NODE4: u32 = 3 + LOG2_NODE4;
const VOXELS_LOG2_NODE5: u32 = VOXELS_LOG2_NODE4 + LOG2_NODE5;

/// A leaf: 8³ voxels from `origin` (a multiple of 8), bit `(x << 6) | (y << 3) | z` of a mask
/// for voxel `origin + (x, y, z)` (`LeafNode::coordToOffset`).
#[derive(Debug, Clone, PartialEq)]
pub struct VdbLeaf {
    /// Its first voxel, in index space.
    pub origin: [i32; 3],
    /// The active voxels.
    pub active: [u64; 8],
    /// The voxels outside the surface: in a level set, its inactive voxels at +background,
    /// the other inactive ones being inside, at −background. Ignored by other grids.
    pub outside: [u64; 8],
}

/// An internal node: `1 << (3 * LOG2)` children or tiles, bit `(x << 2·LOG2) | (y << LOG2) | z`
/// for the child at `(x, y, z)` (`InternalNode::coordToOffset`). Its tiles are inactive; in a
/// level set at +background where `outside` is set, else at −background.
#[derive(Debug, Clone, PartialEq)]
pub struct VdbNode {
    /// Its first voxel, in index space.
    pub origin: [i32; 3],
    /// Which slots hold a child.
    pub children: Vec<u64>,
    /// Which tiles lie outside the surface.
    pub outside: Vec<u64>,
}

/// The active voxels of a file's grids, as OpenVDB's 5-4-3 tree: leaves under nodes of 16³
/// leaves (`InternalNode<_, 4>`), under nodes of 32³ of those (`InternalNode<_, 5>`), under
/// the root. Build it with [`VdbTree::new`]; all lists are in the file's order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct VdbTree {
    /// The leaves, depth first.
    pub leaves: Vec<VdbLeaf>,
    /// The 16³ nodes, depth first.
    pub nodes4: Vec<VdbNode>,
    /// The 32³ nodes, by origin (x, then y, then z: the root's `std::map` order).
    pub nodes5: Vec<VdbNode>,
    /// The root's tiles (regions of 4096³ voxels with no child), all inside the surface and
    /// at −background: a level set's root holds no tile outside (its background is).
    pub inside_tiles: Vec<[i32; 3]>,
}

/// A grid's values, one per active voxel of the tree, in its order.
#[derive(Debug, Clone, Copy)]
pub enum VdbValues<'a> {
    /// Signed distances, negative inside (OpenVDB's `level set` class): inactive voxels and
    /// tiles at ±`half_width`, the background.
    LevelSet {
        /// Active voxels' distances.
        values: &'a [f32],
        /// The narrow band's half width, in world units.
        half_width: f32,
    },
    /// A float grid, background 0.
    Scalar(&'a [f32]),
    /// A `vec3s` grid, background 0.
    Vector(&'a [Vec3]),
}

/// One named grid of a file.
#[derive(Debug, Clone, Copy)]
pub struct VdbGrid<'a> {
    /// Its name (`surface`, `v`, `density`…).
    pub name: &'a str,
    /// Its values.
    pub values: VdbValues<'a>,
}

impl VdbTree {
    /// Places `leaves` (origins multiples of 8, each at most once) in their nodes, tiles
    /// outside; sorts them into the file's order.
    pub fn new(mut leaves: Vec<VdbLeaf>) -> VdbTree {
        leaves.sort_unstable_by_key(|l| file_order(l.origin));
        let mut tree = VdbTree {
            leaves,
            ..VdbTree::default()
        };
        for l in &tree.leaves {
            let o5 = node_origin(l.origin, VOXELS_LOG2_NODE5);
            if tree.nodes5.last().is_none_or(|n| n.origin != o5) {
                tree.nodes5.push(VdbNode::empty(o5, LOG2_NODE5));
            }
            let o4 = node_origin(l.origin, VOXELS_LOG2_NODE4);
            if tree.nodes4.last().is_none_or(|n| n.origin != o4) {
                tree.nodes4.push(VdbNode::empty(o4, LOG2_NODE4));
                let n5 = tree.nodes5.last_mut().expect("a node above");
                set(&mut n5.children, slot(o4, VOXELS_LOG2_NODE4, LOG2_NODE5));
            }
            let n4 = tree.nodes4.last_mut().expect("a node above");
            set(&mut n4.children, slot(l.origin, 3, LOG2_NODE4));
        }
        tree
    }

    /// Active voxels.
    pub fn active_voxels(&self) -> usize {
        self.leaves
            .iter()
            .map(|l| {
                l.active
                    .iter()
                    .map(|w| w.count_ones() as usize)
                    .sum::<usize>()
            })
            .sum()
    }
}

impl VdbNode {
    fn empty(origin: [i32; 3], log2: u32) -> VdbNode {
        let words = 1 << (3 * log2 - 6);
        VdbNode {
            origin,
            children: vec![0; words],
            outside: vec![!0; words],
        }
    }
}

/// The origin of the node of `voxels_log2` voxels a side holding voxel `p`.
pub fn node_origin(p: [i32; 3], voxels_log2: u32) -> [i32; 3] {
    p.map(|c| c & !((1 << voxels_log2) - 1))
}

/// The slot, in a node of `log2` children a side each `child_log2` voxels wide, of the child
/// holding voxel `p` (`InternalNode::coordToOffset`; `LeafNode::coordToOffset` for leaves,
/// `child_log2` 0 and `log2` 3).
pub fn slot(p: [i32; 3], child_log2: u32, log2: u32) -> usize {
    let mask = (1 << log2) - 1;
    let [x, y, z] = p.map(|c| ((c >> child_log2) & mask) as usize);
    (x << (2 * log2)) | (y << log2) | z
}

/// A leaf's place in the file: its 32³ node's origin (the root's order), then its slots.
pub(crate) fn file_order(origin: [i32; 3]) -> ([i32; 3], usize, usize) {
    (
        node_origin(origin, VOXELS_LOG2_NODE5),
        slot(origin, VOXELS_LOG2_NODE4, LOG2_NODE5),
        slot(origin, 3, LOG2_NODE4),
    )
}

fn set(mask: &mut [u64], bit: usize) {
    mask[bit >> 6] |= 1 << (bit & 63);
}

/// Writes `grids`, all over `tree` with voxels `voxel_size` wide, voxel `ijk` centred at
/// `ijk · voxel_size`; `grids` names each once and has one value per active voxel.
pub fn write_vdb(
    tree: &VdbTree,
    voxel_size: f32,
    grids: &[VdbGrid],
    out: &mut impl Write,
) -> io::Result<()> {
    if !(voxel_size.is_finite() && voxel_size > 0.0) {
        return Err(invalid_input(format!(
            "a VDB voxel size must be positive, not {voxel_size}"
        )));
    }
    let active = tree.active_voxels();
    for (i, g) in grids.iter().enumerate() {
        let n = match g.values {
            VdbValues::LevelSet { values, half_width } => {
                if !(half_width.is_finite() && half_width > 0.0) {
                    return Err(invalid_input(format!(
                        "a level set's half width must be positive, not {half_width}"
                    )));
                }
                values.len()
            }
            VdbValues::Scalar(v) => v.len(),
            VdbValues::Vector(v) => v.len(),
        };
        if n != active {
            return Err(invalid_input(format!(
                "the VDB grid '{}' has {n} values for {active} active voxels",
                g.name
            )));
        }
        if g.name.is_empty() || grids[..i].iter().any(|o| o.name == g.name) {
            return Err(invalid_input(format!(
                "VDB grid names must be distinct and not empty: '{}'",
                g.name
            )));
        }
    }
    let mut out = Counted { inner: out, at: 0 };
    header(tree, grids, &mut out)?;
    put(&mut out, &0u32.to_le_bytes())?; // the file's metadata: none
    put(&mut out, &(grids.len() as i32).to_le_bytes())?;
    for grid in grids {
        let grid = Grid {
            tree,
            voxel_size: f64::from(voxel_size),
            grid,
        };
        // GridDescriptor::writeHeader, then writeStreamPos: where the grid, its buffers and
        // it end, measured by writing each part to a counter first.
        string(&mut out, grid.grid.name)?;
        string(&mut out, grid.type_name())?;
        string(&mut out, "")?;
        let start = out.at + 24;
        let blocks = start + size_of_part(|w| grid.head(w))?;
        let end = blocks + size_of_part(|w| grid.buffers(w))?;
        for position in [start, blocks, end] {
            put(&mut out, &(position as i64).to_le_bytes())?;
        }
        grid.head(&mut out)?;
        grid.buffers(&mut out)?;
        debug_assert_eq!(out.at, end);
    }
    Ok(())
}

/// `Archive::writeHeader`: magic, versions, has-grid-offsets, and a UUID (from the content,
/// so that the same grids make the same bytes).
fn header(tree: &VdbTree, grids: &[VdbGrid], out: &mut impl Write) -> io::Result<()> {
    put(out, &MAGIC.to_le_bytes())?;
    put(out, &FILE_VERSION.to_le_bytes())?;
    put(out, &LIBRARY_VERSION[0].to_le_bytes())?;
    put(out, &LIBRARY_VERSION[1].to_le_bytes())?;
    put(out, &[1])?;
    let mut hash = [FxHasher::default(), FxHasher::with_seed(0x5eed)];
    for h in &mut hash {
        for l in &tree.leaves {
            l.origin.iter().for_each(|&c| h.write_i32(c));
            l.active.iter().for_each(|&w| h.write_u64(w));
        }
        for g in grids {
            h.write(g.name.as_bytes());
            if let VdbValues::LevelSet { values, .. } | VdbValues::Scalar(values) = g.values {
                values.iter().for_each(|v| h.write_u32(v.to_bits()));
            }
        }
    }
    let hex = format!("{:016x}{:016x}", hash[0].finish(), hash[1].finish());
    let uuid = format!(
        "{}-{}-{}-{}-{}",
        &hex[..8],
        &hex[8..12],
        &hex[12..16],
        &hex[16..20],
        &hex[20..]
    );
    put(out, uuid.as_bytes())
}

/// One grid being written.
struct Grid<'a> {
    tree: &'a VdbTree,
    voxel_size: f64,
    grid: &'a VdbGrid<'a>,
}

impl Grid<'_> {
    /// `Tree_float_5_4_3` or `Tree_vec3s_5_4_3`.
    fn type_name(&self) -> &'static str {
        match self.grid.values {
            VdbValues::Vector(_) => "Tree_vec3s_5_4_3",
            _ => "Tree_float_5_4_3",
        }
    }

    /// The background's bytes (a value's: 12 for a vector), and −background's.
    fn background(&self) -> (Vec<u8>, Vec<u8>) {
        match self.grid.values {
            VdbValues::LevelSet { half_width, .. } => (
                half_width.to_le_bytes().into(),
                (-half_width).to_le_bytes().into(),
            ),
            _ => (vec![0; self.value_bytes()], vec![0; self.value_bytes()]),
        }
    }

    /// Bytes of one value.
    fn value_bytes(&self) -> usize {
        match self.grid.values {
            VdbValues::Vector(_) => 12,
            _ => 4,
        }
    }

    /// Everything between the offsets and the buffers: compression flags, metadata,
    /// transform, topology.
    fn head(&self, out: &mut impl Write) -> io::Result<()> {
        put(out, &COMPRESS_ACTIVE_MASK.to_le_bytes())?;
        self.metadata(out)?;
        self.transform(out)?;
        self.topology(out)
    }

    /// `MetaMap::writeMeta`: a count, then name, type name, byte size and value of each, in
    /// the names' order (a `std::map`). The `file_*` entries are `GridBase::addStatsMetadata`'s.
    fn metadata(&self, out: &mut impl Write) -> io::Result<()> {
        let (lo, hi) = self.active_bounds();
        let level_set = matches!(self.grid.values, VdbValues::LevelSet { .. });
        let voxels = self.tree.active_voxels() as i64;
        let value_type = match self.grid.values {
            VdbValues::Vector(_) => "vec3s",
            _ => "float",
        };
        let entries: [(&str, &str, Vec<u8>); 10] = [
            (
                "class",
                "string",
                (if level_set { "level set" } else { "unknown" }).into(),
            ),
            ("creator", "string", "splash".into()),
            ("file_bbox_max", "vec3i", vec3i(hi)),
            ("file_bbox_min", "vec3i", vec3i(lo)),
            ("file_compression", "string", "active values".into()),
            (
                "file_mem_bytes",
                "int64",
                self.memory().to_le_bytes().into(),
            ),
            ("file_voxel_count", "int64", voxels.to_le_bytes().into()),
            ("is_saved_as_half_float", "bool", vec![0]),
            ("name", "string", self.grid.name.into()),
            ("value_type", "string", value_type.into()),
        ];
        put(out, &(entries.len() as u32).to_le_bytes())?;
        for (name, kind, value) in entries {
            string(out, name)?;
            string(out, kind)?;
            put(out, &(value.len() as u32).to_le_bytes())?;
            put(out, &value)?;
        }
        Ok(())
    }

    /// The active voxels' bounding box (inclusive), zero when there are none.
    fn active_bounds(&self) -> ([i32; 3], [i32; 3]) {
        let (mut lo, mut hi) = ([i32::MAX; 3], [i32::MIN; 3]);
        for l in &self.tree.leaves {
            for (w, &word) in l.active.iter().enumerate() {
                let mut bits = word;
                while bits != 0 {
                    let n = (w << 6) as i32 | bits.trailing_zeros() as i32;
                    bits &= bits - 1;
                    let v = [n >> 6, (n >> 3) & 7, n & 7];
                    for k in 0..3 {
                        lo[k] = lo[k].min(l.origin[k] + v[k]);
                        hi[k] = hi[k].max(l.origin[k] + v[k]);
                    }
                }
            }
        }
        if lo[0] > hi[0] {
            ([0; 3], [0; 3])
        } else {
            (lo, hi)
        }
    }

    /// What the tree takes in OpenVDB's memory, roughly as `Tree::memUsage` counts it: each
    /// node's values or child pointers (8 bytes a slot) and masks.
    fn memory(&self) -> i64 {
        let t = self.tree;
        let leaf = 512 * self.value_bytes() + 64 + 16;
        let node4 = 4096 * 8 + 2 * 512 + 16;
        let node5 = 32768 * 8 + 2 * 4096 + 16;
        (t.leaves.len() * leaf + t.nodes4.len() * node4 + t.nodes5.len() * node5) as i64
    }

    /// `Transform::write`: the map's type name, then `ScaleTranslateMap::write`'s six vectors
    /// of doubles: translation, scale, voxel size, inverse scale, its square, its half.
    fn transform(&self, out: &mut impl Write) -> io::Result<()> {
        string(out, "UniformScaleTranslateMap")?;
        let s = self.voxel_size;
        for v in [0.0, s, s, 1.0 / s, 1.0 / (s * s), 0.5 / s] {
            for _ in 0..3 {
                put(out, &v.to_le_bytes())?;
            }
        }
        Ok(())
    }

    /// `Tree::writeTopology`: the buffer count, then `RootNode::writeTopology` (background,
    /// tile and child counts, tiles, children), each child's `InternalNode::writeTopology`
    /// (child mask, value mask, tile values, children) down to the leaves' value masks.
    fn topology(&self, out: &mut impl Write) -> io::Result<()> {
        let t = self.tree;
        let (background, minus) = self.background();
        let level_set = matches!(self.grid.values, VdbValues::LevelSet { .. });
        put(out, &1i32.to_le_bytes())?;
        put(out, &background)?;
        let tiles = if level_set { &t.inside_tiles[..] } else { &[] };
        put(out, &(tiles.len() as u32).to_le_bytes())?;
        put(out, &(t.nodes5.len() as u32).to_le_bytes())?;
        for tile in tiles {
            for c in tile {
                put(out, &c.to_le_bytes())?;
            }
            put(out, &minus)?;
            put(out, &[0])?;
        }
        let (mut n4, mut leaf) = (0, 0);
        for n5 in &t.nodes5 {
            for c in n5.origin {
                put(out, &c.to_le_bytes())?;
            }
            self.node(n5, out)?;
            for _ in 0..ones(&n5.children) {
                let node = &t.nodes4[n4];
                n4 += 1;
                self.node(node, out)?;
                for _ in 0..ones(&node.children) {
                    words(out, &t.leaves[leaf].active)?;
                    leaf += 1;
                }
            }
        }
        Ok(())
    }

    /// One internal node's masks and tile values (none active: only the inactive values'
    /// byte, and the mask choosing ±background when a level set has tiles of both signs).
    fn node(&self, node: &VdbNode, out: &mut impl Write) -> io::Result<()> {
        words(out, &node.children)?;
        words(out, &vec![0u64; node.children.len()])?;
        let level_set = matches!(self.grid.values, VdbValues::LevelSet { .. });
        let tiles = node.children.iter().map(|c| !c);
        let outside = tiles.clone().zip(&node.outside).any(|(t, o)| t & o != 0);
        let inside = tiles.zip(&node.outside).any(|(t, o)| t & !o != 0);
        if !level_set || !inside {
            put(out, &[NO_MASK_OR_INACTIVE_VALS])
        } else if !outside {
            put(out, &[NO_MASK_AND_MINUS_BG])
        } else {
            put(out, &[MASK_AND_NO_INACTIVE_VALS])?;
            // The selection mask: set for +background (child slots are skipped on reading).
            words(out, &node.outside)
        }
    }

    /// `Tree::writeBuffers`: each leaf's value mask, its inactive values' byte (and mask),
    /// and its active values.
    fn buffers(&self, out: &mut impl Write) -> io::Result<()> {
        let mut next = 0;
        let mut block: Vec<u8> = Vec::with_capacity(512 * 12 + 256);
        for leaf in &self.tree.leaves {
            block.clear();
            leaf.active
                .iter()
                .for_each(|w| block.extend(w.to_le_bytes()));
            let count = ones(&leaf.active);
            if let VdbValues::LevelSet { .. } = self.grid.values {
                let inactive = leaf.active.map(|w| !w);
                let outside = inactive.iter().zip(&leaf.outside).any(|(i, o)| i & o != 0);
                let inside = inactive.iter().zip(&leaf.outside).any(|(i, o)| i & !o != 0);
                if !inside {
                    block.push(NO_MASK_OR_INACTIVE_VALS);
                } else if !outside {
                    block.push(NO_MASK_AND_MINUS_BG);
                } else {
                    block.push(MASK_AND_NO_INACTIVE_VALS);
                    // Bits of active voxels are ignored on reading; clear them as OpenVDB does.
                    for (o, i) in leaf.outside.iter().zip(inactive) {
                        block.extend((o & i).to_le_bytes());
                    }
                }
            } else {
                block.push(NO_MASK_OR_INACTIVE_VALS);
            }
            match self.grid.values {
                VdbValues::LevelSet { values, .. } | VdbValues::Scalar(values) => values
                    [next..next + count]
                    .iter()
                    .for_each(|v| block.extend(v.to_le_bytes())),
                VdbValues::Vector(values) => values[next..next + count]
                    .iter()
                    .flat_map(|v| v.to_array())
                    .for_each(|v| block.extend(v.to_le_bytes())),
            }
            next += count;
            put(out, &block)?;
        }
        Ok(())
    }
}

fn ones(mask: &[u64]) -> usize {
    mask.iter().map(|w| w.count_ones() as usize).sum()
}

/// `NodeMask::save`: the words, little-endian.
fn words(out: &mut impl Write, mask: &[u64]) -> io::Result<()> {
    let bytes: Vec<u8> = mask.iter().flat_map(|w| w.to_le_bytes()).collect();
    put(out, &bytes)
}

fn vec3i(v: [i32; 3]) -> Vec<u8> {
    v.iter().flat_map(|c| c.to_le_bytes()).collect()
}

/// `writeString`: a `uint32` length, then the bytes.
fn string(out: &mut impl Write, s: &str) -> io::Result<()> {
    put(out, &(s.len() as u32).to_le_bytes())?;
    put(out, s.as_bytes())
}

fn put(out: &mut impl Write, bytes: &[u8]) -> io::Result<()> {
    out.write_all(bytes)
}

/// Bytes `part` writes.
fn size_of_part(part: impl FnOnce(&mut Counted<io::Sink>) -> io::Result<()>) -> io::Result<u64> {
    let mut sink = io::sink();
    let mut counter = Counted {
        inner: &mut sink,
        at: 0,
    };
    part(&mut counter)?;
    Ok(counter.at)
}

/// A stream that counts the bytes written through it.
struct Counted<'a, W: Write> {
    inner: &'a mut W,
    at: u64,
}

impl<W: Write> Write for Counted<'_, W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.at += n as u64;
        Ok(n)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.inner.flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn leaf(origin: [i32; 3]) -> VdbLeaf {
        VdbLeaf {
            origin,
            active: [1; 8],
            outside: [!0; 8],
        }
    }

    /// Leaves land in the root's, then the nodes' slot order, each node once.
    #[test]
    fn leaves_are_grouped_in_file_order() {
        let tree = VdbTree::new(vec![
            leaf([4096, 0, 0]),
            leaf([8, 0, 0]),
            leaf([0, 0, 8]),
            leaf([-8, 0, 0]),
            leaf([0, 128, 0]),
        ]);
        let origins: Vec<[i32; 3]> = tree.leaves.iter().map(|l| l.origin).collect();
        assert_eq!(
            origins,
            [[-8, 0, 0], [0, 0, 8], [8, 0, 0], [0, 128, 0], [4096, 0, 0]]
        );
        let n5: Vec<[i32; 3]> = tree.nodes5.iter().map(|n| n.origin).collect();
        assert_eq!(n5, [[-4096, 0, 0], [0, 0, 0], [4096, 0, 0]]);
        assert_eq!(tree.nodes4.len(), 4);
        assert_eq!(ones(&tree.nodes4[1].children), 2);
        assert_eq!(slot([0, 0, 8], 3, 4), 1);
        assert_eq!(slot([8, 0, 0], 3, 4), 256);
        assert_eq!(tree.active_voxels(), 5 * 8);
    }

    /// The offsets in a descriptor are where the grid, its buffers and its end are.
    #[test]
    fn descriptor_offsets_point_at_the_grid() {
        let tree = VdbTree::new(vec![leaf([0, 0, 0]), leaf([16, -8, 0])]);
        let values = vec![0.5f32; tree.active_voxels()];
        let vectors = vec![Vec3::X; tree.active_voxels()];
        let grids = [
            VdbGrid {
                name: "surface",
                values: VdbValues::LevelSet {
                    values: &values,
                    half_width: 3.0,
                },
            },
            VdbGrid {
                name: "v",
                values: VdbValues::Vector(&vectors),
            },
        ];
        let mut bytes = Vec::new();
        write_vdb(&tree, 1.0, &grids, &mut bytes).unwrap();
        let i64_at = |at: usize| i64::from_le_bytes(bytes[at..at + 8].try_into().unwrap());
        // Header: 8 + 4 + 8 + 1 + 36, metadata count 4, grid count 4.
        let mut at = 65;
        for (name, kind) in [("surface", "Tree_float_5_4_3"), ("v", "Tree_vec3s_5_4_3")] {
            at += 4 + name.len() + 4 + kind.len() + 4;
            let (start, end) = (i64_at(at) as usize, i64_at(at + 16) as usize);
            assert_eq!(start, at + 24);
            assert_eq!(
                &bytes[start..start + 4],
                &COMPRESS_ACTIVE_MASK.to_le_bytes()
            );
            at = end;
        }
        assert_eq!(at, bytes.len());
        let short = VdbGrid {
            name: "surface",
            values: VdbValues::Scalar(&values[1..]),
        };
        let error = write_vdb(&tree, 1.0, &[short], &mut Vec::new()).unwrap_err();
        assert!(
            error.to_string().contains("values for 16 active voxels"),
            "{error}"
        );
    }
}
