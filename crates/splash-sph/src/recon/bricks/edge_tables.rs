//! The edge tables of the band's bricks, the counting pass of the triangulation (Sec. 4.2):
//! which grid edges carry a mesh vertex (the field changes sign along them and one of the four
//! cells around them is triangulated) and how many triangles and surface cells each brick
//! has. Band closure works them out as it scans the bricks, so the triangulation starts from
//! its last scan.

use glam::IVec3;
use rayon::prelude::*;

use super::band::{BRICK, Band, local_vertex};
use super::brick_neighbours::NeighbourWalk;
use super::brick_signs::Signs;
use super::surface_cells::BrickCells;
use crate::mesh::marching_cubes::cases;

/// The edge vertices owned by one brick: bit `3 * local_index + axis` marks an edge that holds
/// one, numbered in bit order from `first`; and where the brick's triangles start.
#[derive(Clone)]
pub struct BrickEdges {
    bits: [u64; 24],
    /// Vertices in the words before each word.
    ranks: [u32; 24],
    pub first: u32,
    pub vertices: u32,
    /// Surface cells: crossed cells, each with triangles.
    pub cells: u32,
    pub triangles: usize,
    pub first_triangle: usize,
}

impl BrickEdges {
    pub fn id(&self, local: usize, axis: usize) -> u32 {
        let bit = 3 * local + axis;
        let (w, b) = (bit / 64, bit % 64);
        debug_assert!(self.bits[w] >> b & 1 == 1, "edge without a vertex");
        self.first + self.ranks[w] + (self.bits[w] & ((1u64 << b) - 1)).count_ones()
    }

    /// The lowest and highest local coordinates of the vertices whose edges hold one.
    pub fn extent(&self) -> (IVec3, IVec3) {
        let (mut lo, mut hi) = (IVec3::splat(BRICK), IVec3::splat(-1));
        self.each(|local, _| {
            let l = local_vertex(local);
            (lo, hi) = (lo.min(l), hi.max(l));
        });
        (lo, hi)
    }

    /// The positions of the edges that hold a vertex, as (local index, axis), in bit order.
    pub fn each(&self, mut f: impl FnMut(usize, usize)) {
        for (w, &word) in self.bits.iter().enumerate() {
            let mut bits = word;
            while bits != 0 {
                let bit = 64 * w + bits.trailing_zeros() as usize;
                bits &= bits - 1;
                f(bit / 3, bit % 3);
            }
        }
    }
}

/// Bytes the triangulation holds per brick besides its vertices: the edge table.
pub const PER_BRICK_EDGES: u64 = size_of::<BrickEdges>() as u64;

/// One edge table per brick of a band, in brick order; none for bricks without vertices or
/// triangles.
#[derive(Clone)]
pub struct EdgeTables(pub Vec<Option<Box<BrickEdges>>>);

impl EdgeTables {
    /// The tables of every brick of `band`, whose values have the sign planes `signs`.
    pub fn of(band: &Band, signs: &Signs) -> EdgeTables {
        EdgeTables(
            band.bricks
                .par_iter()
                .map_init(
                    || (BrickCells::new(), NeighbourWalk::new(&band.bricks)),
                    |(cells, walk), &brick| {
                        let neighbours = walk.around(brick);
                        if !signs.owns_inside_corner(&neighbours) {
                            return None;
                        }
                        cells.fill(band, signs, neighbours);
                        table(cells)
                    },
                )
                .collect(),
        )
    }

    /// The tables of the bricks `old` moved to their places among `new`, which holds them all
    /// (both sorted by (z, y, x)); the other bricks of `new` get none.
    pub fn regrid(self, old: &[IVec3], new: &[IVec3]) -> EdgeTables {
        let mut moved = Vec::with_capacity(new.len());
        let mut tables = old.iter().zip(self.0).peekable();
        for b in new {
            moved.push(match tables.peek() {
                Some((o, _)) if *o == b => tables.next().and_then(|(_, t)| t),
                _ => None,
            });
        }
        debug_assert!(tables.next().is_none(), "every old brick is among the new");
        EdgeTables(moved)
    }
}

/// The edge table of the brick `cells` were filled for, if it has vertices or triangles.
pub fn table(cells: &BrickCells) -> Option<Box<BrickEdges>> {
    let e = count_brick(cells);
    (e.vertices > 0 || e.triangles > 0).then(|| Box::new(e))
}

/// The edge table of a brick (which of the sign-changing edges leaving its vertices in +x,
/// +y, +z have a vertex: those where at least one of the four cells around the edge is
/// complete), the number of its triangles and of its surface cells; `cells` filled for it.
fn count_brick(cells: &BrickCells) -> BrickEdges {
    let mut edges = BrickEdges {
        bits: [0; 24],
        ranks: [0; 24],
        first: 0,
        vertices: 0,
        cells: 0,
        triangles: 0,
        first_triangle: 0,
    };
    for z in 0..BRICK as usize {
        for y in 0..BRICK as usize {
            // The row's 8 vertices × 3 axes, at bit 3 * local_index + axis.
            let row = (0..3).fold(0u64, |row, axis| {
                row | u64::from(SPREAD[cells.edge_row(axis, y, z) as usize]) << axis
            });
            let bit = 3 * BRICK as usize * (y + BRICK as usize * z);
            let (w, b) = (bit / 64, bit % 64);
            edges.bits[w] |= row << b;
            if b + 24 > 64 {
                edges.bits[w + 1] |= row >> (64 - b);
            }
        }
    }
    let table = cases();
    cells.crossed(|_, case| {
        let n = table[case].triangles().len();
        edges.triangles += n;
        edges.cells += u32::from(n > 0);
    });
    let mut count = 0;
    for (rank, bits) in edges.ranks.iter_mut().zip(&edges.bits) {
        *rank = count;
        count += bits.count_ones();
    }
    edges.vertices = count;
    edges
}

/// Bit `i` of a byte moved to bit `3i`.
const SPREAD: [u32; 256] = {
    let mut table = [0; 256];
    let mut byte = 0;
    while byte < 256 {
        let mut i = 0;
        while i < 8 {
            table[byte] |= ((byte as u32 >> i) & 1) << (3 * i);
            i += 1;
        }
        byte += 1;
    }
    table
};
