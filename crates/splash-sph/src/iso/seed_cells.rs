//! Seed cells (Sec. III-C): for every pair of particles within a reach of each other whose raw values
//! lie on both sides of the level, every virtual cell the segment between them passes through
//! (a 3D grid walk, Amanatides & Woo). By the intermediate value theorem for the raw data, each
//! connected component of the isosurface gets at least one seed.

use glam::{DVec3, IVec3, Vec3};
use rayon::prelude::*;

use super::sph_interpolant::Interpolant;
use super::virtual_grid::VirtualGrid;

/// The seed cells of `level` in lexicographic (z, y, x) order, each once.
pub(crate) fn seed_cells(
    it: &Interpolant,
    grid: &VirtualGrid,
    level: f64,
    reach: f32,
) -> Vec<IVec3> {
    let h = &it.handlers;
    let values = &h.channels[it.channels.value];
    let supports = &h.channels[it.channels.support];
    let mut seeds: Vec<IVec3> = (0..h.positions.len())
        .into_par_iter()
        .fold(Vec::new, |mut out, i| {
            let (p, above) = (h.positions[i], f64::from(values[i]) >= level);
            // Inclusive with a rounding margin, so lattice neighbours at exactly the reach pair.
            let reach = reach * supports[i] * (1.0 + 1e-4);
            let c = h.cell_of(p);
            h.for_each_in_cells(c - IVec3::ONE, c + IVec3::ONE, |range| {
                for j in range.filter(|&j| j > i) {
                    let q = h.positions[j];
                    if (f64::from(values[j]) >= level) != above
                        && (q - p).length_squared() <= reach * reach
                    {
                        walk(grid, p, q, |cell| out.push(cell));
                    }
                }
            });
            out
        })
        .reduce(Vec::new, |mut a, mut b| {
            a.append(&mut b);
            a
        });
    seeds.par_sort_unstable_by_key(|c| [c.z, c.y, c.x]);
    seeds.dedup();
    seeds
}

/// Calls `f` with every cell the segment from `p` to `q` passes through, from `p`'s to `q`'s.
pub(crate) fn walk(grid: &VirtualGrid, p: Vec3, q: Vec3, mut f: impl FnMut(IVec3)) {
    let (a, b) = (p.as_dvec3() / grid.cell, q.as_dvec3() / grid.cell);
    let mut cell = a.floor().as_ivec3();
    let end = b.floor().as_ivec3();
    let d = b - a;
    let step = IVec3::new(sign(d.x), sign(d.y), sign(d.z));
    // Parameter t of the next cell boundary on each axis, and t between boundaries.
    let next = |k: usize| {
        if d[k] == 0.0 {
            f64::INFINITY
        } else {
            let boundary = f64::from(cell[k] + i32::from(d[k] > 0.0));
            (boundary - a[k]) / d[k]
        }
    };
    let mut t_max = DVec3::new(next(0), next(1), next(2));
    let t_delta = DVec3::new(1.0 / d.x.abs(), 1.0 / d.y.abs(), 1.0 / d.z.abs());
    f(cell);
    // At most one step per boundary crossed: the walk ends even if rounding misses `end`.
    let steps = (end - cell).abs().element_sum();
    for _ in 0..steps {
        if cell == end {
            break;
        }
        let k = if t_max.x <= t_max.y && t_max.x <= t_max.z {
            0
        } else if t_max.y <= t_max.z {
            1
        } else {
            2
        };
        cell[k] += step[k];
        t_max[k] += t_delta[k];
        f(cell);
    }
}

fn sign(x: f64) -> i32 {
    if x > 0.0 {
        1
    } else if x < 0.0 {
        -1
    } else {
        0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_walk_visits_face_neighbours_from_one_end_to_the_other() {
        let grid = VirtualGrid { cell: 0.1 };
        let mut cells = Vec::new();
        walk(
            &grid,
            Vec3::new(0.05, 0.05, 0.05),
            Vec3::new(0.37, 0.22, -0.08),
            |c| cells.push(c),
        );
        assert_eq!(cells[0], IVec3::ZERO);
        assert_eq!(*cells.last().unwrap(), IVec3::new(3, 2, -1));
        assert_eq!(cells.len(), 7);
        for w in cells.windows(2) {
            assert_eq!((w[1] - w[0]).abs().element_sum(), 1, "{cells:?}");
        }
    }
}
