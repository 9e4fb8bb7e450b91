//! The surface cells of one brick (Sec. 4.2: cells whose eight corners are all surface
//! vertices), their Marching Cubes cases and the edges that carry mesh vertices, worked out
//! from the sign planes of the brick and its 26 neighbours with bit operations on rows of
//! vertices: a brick's 512 cells cost a few hundred word operations, and only the cells the
//! surface crosses are visited one by one.

use glam::IVec3;

use super::band::{BRICK, Band};
use super::brick_signs::Signs;
#[cfg(doc)]
use super::halo::neighbour_slot;

/// Rows cover local coordinates −1..=9, as the halo does: bit `x + 1` of a row is vertex `x`.
const SIDE: usize = BRICK as usize + 3;
/// Cells with lowest corner −1..=8 on each axis.
const CELLS: usize = SIDE - 1;
/// The corners (bit `c`) of each cube face, per axis and side.
const FACES: [[usize; 2]; 3] = [[0x55, 0xaa], [0x33, 0xcc], [0x0f, 0xf0]];

/// Which vertices around one brick are in the band and inside, and which cells are complete.
pub struct BrickCells {
    /// Index of the brick at offset (dx, dy, dz) ∈ {−1, 0, 1}³, if it exists.
    pub neighbours: [Option<usize>; 27],
    /// Vertices with a value, row (y, z) at `[z + 1][y + 1]`.
    present: [[u16; SIDE]; SIDE],
    /// Vertices with a negative value, rows as `present`.
    inside: [[u16; SIDE]; SIDE],
    /// Cells whose eight corners are present: row (y, z) at `[z + 1][y + 1]`, bit `x + 1`.
    complete: [[u16; CELLS]; CELLS],
}

impl Default for BrickCells {
    fn default() -> BrickCells {
        BrickCells::new()
    }
}

impl BrickCells {
    pub fn new() -> BrickCells {
        BrickCells {
            neighbours: [None; 27],
            present: [[0; SIDE]; SIDE],
            inside: [[0; SIDE]; SIDE],
            complete: [[0; CELLS]; CELLS],
        }
    }

    /// The cells of the brick whose neighbours (by [`neighbour_slot`]) are `neighbours`.
    pub fn fill(&mut self, band: &Band, signs: &Signs, neighbours: [Option<usize>; 27]) {
        self.present = [[0; SIDE]; SIDE];
        self.inside = [[0; SIDE]; SIDE];
        self.neighbours = neighbours;
        for (n, slot) in neighbours.into_iter().enumerate() {
            let d = IVec3::new(n as i32 % 3, n as i32 / 3 % 3, n as i32 / 9) - 1;
            let Some(b) = slot else { continue };
            let (present, inside) = signs.planes(&band.masks[b], b);
            // A neighbour's row of 8 bits lands at halo bit 0 (its x = 7), 1..=8 or 9..=10.
            let place = |row: u64| -> u16 {
                let row = row as u8 as u16;
                match d.x {
                    -1 => row >> 7,
                    0 => row << 1,
                    _ => (row & 3) << 9,
                }
            };
            for (hz, lz) in span(d.z) {
                let (p, i) = (present[lz], inside[lz]);
                for (hy, ly) in span(d.y) {
                    self.present[hz][hy] |= place(p >> (BRICK as usize * ly));
                    self.inside[hz][hy] |= place(i >> (BRICK as usize * ly));
                }
            }
        }
        for z in 0..CELLS {
            for y in 0..CELLS {
                let p = &self.present;
                let c = p[z][y] & p[z][y + 1] & p[z + 1][y] & p[z + 1][y + 1];
                self.complete[z][y] = c & (c >> 1);
            }
        }
    }

    /// Whether the cell with lowest corner `l` (−1..=8 on each axis) has all corners present.
    #[inline]
    pub fn complete(&self, l: IVec3) -> bool {
        let s = (l + 1).as_uvec3();
        self.complete[s.z as usize][s.y as usize] >> s.x & 1 == 1
    }

    /// Whether vertex `v` (−1..=9 on each axis) has a value.
    #[inline]
    pub fn present(&self, v: IVec3) -> bool {
        let s = (v + 1).as_uvec3();
        self.present[s.z as usize][s.y as usize] >> s.x & 1 == 1
    }

    /// Calls `f` with each of the brick's own cells (lowest corner in it) that the surface
    /// crosses, complete with inside and outside corners, and its case, in local index order.
    #[inline]
    pub fn crossed(&self, mut f: impl FnMut(IVec3, usize)) {
        for z in 0..BRICK {
            for y in 0..BRICK {
                let mut bits = self.crossed_row(y as usize + 1, z as usize + 1);
                while bits != 0 {
                    let l = IVec3::new(bits.trailing_zeros() as i32 - 1, y, z);
                    bits &= bits - 1;
                    f(l, self.case(l));
                }
            }
        }
    }

    /// Crossed cells of halo row (`hy`, `hz`) among the brick's own, bit `x + 1`.
    #[inline]
    fn crossed_row(&self, hy: usize, hz: usize) -> u16 {
        let i = &self.inside;
        let any = i[hz][hy] | i[hz][hy + 1] | i[hz + 1][hy] | i[hz + 1][hy + 1];
        let all = i[hz][hy] & i[hz][hy + 1] & i[hz + 1][hy] & i[hz + 1][hy + 1];
        let (any, all) = (any | (any >> 1), all & (all >> 1));
        self.complete[hz][hy] & any & !all & 0x1fe
    }

    /// Marching Cubes case of the cell with lowest corner `l` (bit `c` for inside corner `c`).
    #[inline]
    pub fn case(&self, l: IVec3) -> usize {
        let s = (l + 1).as_uvec3();
        let (x, y, z) = (s.x, s.y as usize, s.z as usize);
        let i = &self.inside;
        let pair = |row: u16| usize::from(row >> x & 3);
        pair(i[z][y]) | pair(i[z][y + 1]) << 2 | pair(i[z + 1][y]) << 4 | pair(i[z + 1][y + 1]) << 6
    }

    /// The edges along `axis` leaving the brick's vertices (`y`, `z`) (bit `x`) that carry a
    /// mesh vertex: the sign changes along them and one of the four cells around them is
    /// complete.
    pub fn edge_row(&self, axis: usize, y: usize, z: usize) -> u8 {
        let (hy, hz) = (y + 1, z + 1);
        let (p, i, c) = (&self.present, &self.inside, &self.complete);
        let (crossed, near) = match axis {
            0 => {
                let (p, i) = (p[hz][hy], i[hz][hy]);
                let near = c[hz][hy] | c[hz][hy - 1] | c[hz - 1][hy] | c[hz - 1][hy - 1];
                (p & (p >> 1) & (i ^ (i >> 1)), near)
            }
            1 => {
                let near = c[hz][hy] | c[hz - 1][hy];
                let crossed = p[hz][hy] & p[hz][hy + 1] & (i[hz][hy] ^ i[hz][hy + 1]);
                (crossed, near | (near << 1))
            }
            _ => {
                let near = c[hz][hy] | c[hz][hy - 1];
                let crossed = p[hz][hy] & p[hz + 1][hy] & (i[hz][hy] ^ i[hz + 1][hy]);
                (crossed, near | (near << 1))
            }
        };
        ((crossed & near) >> 1) as u8
    }

    /// Whether the surface crosses face (`axis`, `side`) of a cell of case `case`.
    #[inline]
    pub fn face_crossed(case: usize, axis: usize, side: usize) -> bool {
        let face = FACES[axis][side];
        let on = case & face;
        on != 0 && on != face
    }
}

/// Pairs (halo index, the neighbour's local coordinate) along one axis for a neighbour at
/// offset `d`: its last layer, all of it, or its first two.
fn span(d: i32) -> impl Iterator<Item = (usize, usize)> {
    let (h, l, n) = match d {
        -1 => (0, 7, 1),
        0 => (1, 0, 8),
        _ => (9, 0, 2),
    };
    (0..n).map(move |k| (h + k, l + k))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::marching_cubes::case_index;
    use crate::recon::bricks::band::BRICK_VERTICES;
    use crate::recon::bricks::brick_neighbours::NeighbourWalk;
    use crate::recon::bricks::brick_values::BrickValues;
    use crate::recon::bricks::halo::{Halo, offset};
    use glam::Vec3;

    /// Bits against the values, on a random field with holes, over every cell and edge.
    #[test]
    fn bits_agree_with_the_values() {
        let band = Band::full(Vec3::ZERO, Vec3::splat(2.25), 0.1, 0.0).unwrap();
        let mut uniform = crate::tests::common::uniform(7u64);
        let mut next = move || uniform() - 0.5;
        let dense: Vec<[f32; BRICK_VERTICES]> = (0..band.bricks.len())
            .map(|_| {
                std::array::from_fn(|_| {
                    let v = next();
                    if v > 0.4 { f32::NAN } else { v }
                })
            })
            .collect();
        let values = BrickValues::sample(&band, || (), |_, b| dense[b]).unwrap();
        let signs = Signs::of(&band, &values);
        let (mut cells, mut halo) = (BrickCells::new(), Halo::new());
        let mut walk = NeighbourWalk::new(&band.bricks);
        let mut crossed = 0;
        for &brick in &band.bricks {
            cells.fill(&band, &signs, walk.around(brick));
            halo.fill(
                &band,
                &values,
                &cells.neighbours,
                IVec3::splat(-1),
                IVec3::splat(9),
            );
            let range = |a, b| {
                (a..=b).flat_map(move |z| {
                    (a..=b).flat_map(move |y| (a..=b).map(move |x| IVec3::new(x, y, z)))
                })
            };
            for v in range(-1, 9) {
                assert_eq!(cells.present(v), !halo.at(v).is_nan(), "{brick} {v}");
            }
            for l in range(-1, 8) {
                let complete = (0..8).all(|c| !halo.at(l + offset(c)).is_nan());
                assert_eq!(cells.complete(l), complete, "{brick} {l}");
            }
            let mut expected = Vec::new();
            for l in range(0, 7).map(|l| IVec3::new(l.x, l.y, l.z)) {
                let corners: [f32; 8] = std::array::from_fn(|c| halo.at(l + offset(c)));
                let case = case_index(&corners);
                if cells.complete(l) && case != 0 && case != 255 {
                    expected.push((l, case));
                }
            }
            expected.sort_by_key(|(l, _)| (l.z, l.y, l.x));
            let mut got = Vec::new();
            cells.crossed(|l, case| got.push((l, case)));
            assert_eq!(got, expected, "{brick}");
            crossed += got.len();
            for l in range(0, 7) {
                for axis in 0..3 {
                    let e = IVec3::AXES[axis];
                    let (v0, v1) = (halo.at(l), halo.at(l + e));
                    let sign = !v0.is_nan() && !v1.is_nan() && (v0 < 0.0) != (v1 < 0.0);
                    let (u, w) = (IVec3::AXES[(axis + 1) % 3], IVec3::AXES[(axis + 2) % 3]);
                    let near = [l, l - u, l - w, l - u - w]
                        .into_iter()
                        .any(|c| cells.complete(c));
                    let bit = cells.edge_row(axis, l.y as usize, l.z as usize) >> l.x & 1;
                    assert_eq!(bit == 1, sign && near, "{brick} {l} {axis}");
                }
            }
        }
        assert!(crossed > 100, "{crossed}");
    }
}
