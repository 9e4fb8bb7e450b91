//! The 26 neighbours of the band's bricks (Sec. 4.1's band, stored as bricks), for bricks
//! visited in (z, y, x) order: found by walking the sorted brick list with one cursor per row
//! of three neighbours instead of 27 hash lookups, as a large band's index does not fit in
//! cache while the walk reads the list in order.

use glam::IVec3;

fn key(b: IVec3) -> (i32, i32, i32) {
    (b.z, b.y, b.x)
}

/// Cursors into a brick list sorted by (z, y, x), one per neighbour row (dy, dz).
pub struct NeighbourWalk<'a> {
    bricks: &'a [IVec3],
    rows: [usize; 9],
    last: Option<IVec3>,
}

impl<'a> NeighbourWalk<'a> {
    pub fn new(bricks: &'a [IVec3]) -> NeighbourWalk<'a> {
        NeighbourWalk {
            bricks,
            rows: [0; 9],
            last: None,
        }
    }

    /// Index of the brick at `brick + d` for each d ∈ {−1, 0, 1}³ (by
    /// [`neighbour_slot`](super::halo::neighbour_slot)), if it exists. Fastest when called
    /// with increasing bricks; any order gives the same answer.
    pub fn around(&mut self, brick: IVec3) -> [Option<usize>; 27] {
        let restart = self.last.is_none_or(|last| key(brick) < key(last));
        self.last = Some(brick);
        let mut out = [None; 27];
        for (r, cursor) in self.rows.iter_mut().enumerate() {
            let first = brick + IVec3::new(-1, r as i32 % 3 - 1, r as i32 / 3 - 1);
            *cursor = if restart {
                self.bricks.partition_point(|&b| key(b) < key(first))
            } else {
                gallop(self.bricks, *cursor, key(first))
            };
            let mut k = *cursor;
            for dx in 0..3 {
                if self.bricks.get(k) == Some(&(first + IVec3::X * dx)) {
                    out[3 * r + dx as usize] = Some(k);
                    k += 1;
                }
            }
        }
        out
    }
}

/// The first position at or after `from` whose brick is not below `target`.
fn gallop(bricks: &[IVec3], from: usize, target: (i32, i32, i32)) -> usize {
    let below = |k: usize| bricks.get(k).is_some_and(|&b| key(b) < target);
    if !below(from) {
        return from;
    }
    let mut step = 1;
    while below(from + step) {
        step *= 2;
    }
    // bricks[from + step / 2] is below the target, bricks[from + step] is not (or past the end).
    let lo = from + step / 2 + 1;
    let hi = (from + step).min(bricks.len());
    lo + bricks[lo..hi].partition_point(|&b| key(b) < target)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recon::bricks::band::Band;
    use crate::recon::bricks::halo::neighbour_slot;
    use glam::Vec3;

    #[test]
    fn walk_finds_what_the_index_finds() {
        // Scattered particles: bricks in runs, gaps, and lone ones.
        let mut next = crate::tests::common::uniform(3u64);
        let points: Vec<Vec3> = (0..300)
            .map(|_| crate::tests::common::uniform_point(&mut next) * 6.0)
            .collect();
        let band = Band::around(&points, 0.1, 0.3).unwrap();
        let check = |walk: &mut NeighbourWalk, brick: IVec3| {
            let got = walk.around(brick);
            for n in 0..27 {
                let d = IVec3::new(n % 3, n / 3 % 3, n / 9) - 1;
                let slot = neighbour_slot(d);
                assert_eq!(got[slot], band.brick_index(brick + d), "{brick} {d}");
            }
        };
        let mut walk = NeighbourWalk::new(&band.bricks);
        for &b in &band.bricks {
            check(&mut walk, b);
        }
        // Out of order, and bricks not in the band.
        for &b in band.bricks.iter().rev().step_by(7) {
            check(&mut walk, b + IVec3::new(0, 2, 0));
            check(&mut walk, b);
        }
        assert!(band.bricks.len() > 100, "{}", band.bricks.len());
    }
}
