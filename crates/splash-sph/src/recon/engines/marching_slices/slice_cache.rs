//! The slice caches of Marching Slices (Rosenberg & Birdwell 2008, Sec. 4, Fig. 3): for one
//! slice of corners, a corner index array with the done flags of the cubes above and below,
//! and a corner cache of the corners computed so far.

use glam::Vec3;

/// Done flag of the cube above the slice at (x, y), in the corner index array.
pub const DONE_ABOVE: u32 = 1 << 31;
/// Done flag of the cube below.
pub const DONE_BELOW: u32 = 1 << 30;
/// The rest of an entry: 1 + the corner's place in the corner cache, 0 if not computed.
const INDEX: u32 = DONE_BELOW - 1;
/// An edge without a vertex.
pub const NO_VERTEX: u32 = u32::MAX;

/// A computed corner.
#[derive(Debug, Clone, Copy)]
pub struct Corner {
    /// Where it is in the slice, to clear the index array when the slice is freed.
    pub at: [u16; 2],
    pub value: f32,
    /// The field's gradient, computed when a vertex needs it (NaN until then).
    pub gradient: Vec3,
    /// The vertices on the edges to the corners at +x, +y and +z.
    pub vertices: [u32; 3],
}

#[derive(Default)]
pub struct SliceCache {
    index: Vec<u32>,
    pub corners: Vec<Corner>,
}

impl SliceCache {
    /// An empty slice of `side` × `side` corners, reusing `recycled`'s memory if given.
    pub fn new(side: usize, recycled: Option<SliceCache>) -> SliceCache {
        let mut s = recycled.unwrap_or_default();
        if s.index.len() != side * side {
            s.index = vec![0; side * side];
        }
        s
    }

    /// Clears the entries set so far, through the corner cache, for reuse.
    pub fn reset(&mut self, side: usize) {
        for c in &self.corners {
            self.index[c.at[1] as usize * side + c.at[0] as usize] = 0;
        }
        self.corners.clear();
    }

    pub fn entry(&self, i: usize) -> u32 {
        self.index[i]
    }

    pub fn set_flag(&mut self, i: usize, flag: u32) {
        self.index[i] |= flag;
    }

    /// The corner cached at entry `i`, if computed.
    pub fn corner(&self, i: usize) -> Option<u32> {
        (self.index[i] & INDEX).checked_sub(1)
    }

    /// Caches the corner at entry `i`, which has none yet; returns its place.
    pub fn insert(&mut self, i: usize, corner: Corner) -> u32 {
        let id = self.corners.len() as u32;
        self.corners.push(corner);
        self.index[i] = (self.index[i] & !INDEX) | (id + 1);
        id
    }

    /// Bytes held: index array and corner cache (the paper's "render memory").
    pub fn heap_bytes(&self) -> usize {
        self.index.capacity() * size_of::<u32>() + self.corners.capacity() * size_of::<Corner>()
    }
}
