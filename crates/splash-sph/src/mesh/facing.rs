//! Vertices whose normals face each other within a reach: the two sides of a thin sheet, two
//! bodies about to touch. The clearance asks how near (how far the volume steps may move a
//! vertex) and where (which faces the guard against crossings tests).

use glam::{IVec3, Vec3};
use rayon::prelude::*;
use rustc_hash::FxHashMap;

use crate::neighbours::{CellKeys, cell_of};

/// Normals that turn more than this against each other face each other (120°).
pub(crate) const FACING: f32 = -0.5;

/// The vertices in cells at least `reach` wide, sorted by cell: each vertex's 27 cells hold
/// every vertex within the reach.
pub(crate) struct FacingGrid {
    keys: CellKeys,
    cell: f32,
    /// `key << 32 | vertex`, sorted.
    order: Vec<u64>,
    /// Each occupied cell's run of `order`.
    runs: Vec<(usize, usize)>,
    cells: FxHashMap<u32, (usize, usize)>,
}

impl FacingGrid {
    /// The grid of the `vertices` that are `used` (and finite), or None when there are none or
    /// the reach is not a positive length.
    pub(crate) fn new(
        vertices: &[Vec3],
        used: impl Fn(usize) -> bool + Sync,
        reach: f32,
    ) -> Option<FacingGrid> {
        let used = |v: usize| used(v) && vertices[v].is_finite();
        let bounds = (0..vertices.len())
            .filter(|&v| used(v))
            .fold((Vec3::MAX, Vec3::MIN), |(lo, hi), v| {
                (lo.min(vertices[v]), hi.max(vertices[v]))
            });
        // No vertex used leaves the box empty.
        if !(reach.is_finite() && reach > 0.0 && bounds.0.cmple(bounds.1).all()) {
            return None;
        }
        // The 27 cells around a vertex's hold all within the reach, however wide they are.
        let (keys, cell) = CellKeys::fitting(bounds, reach);
        let mut order: Vec<u64> = (0..vertices.len() as u32)
            .into_par_iter()
            .filter(|&v| used(v as usize))
            .map(|v| {
                u64::from(keys.packed(cell_of(vertices[v as usize], cell))) << 32 | u64::from(v)
            })
            .collect();
        order.par_sort_unstable();
        // Each occupied cell's run of `order`, by its key.
        let mut runs: Vec<(usize, usize)> = Vec::new();
        let key = |i: usize| (order[i] >> 32) as u32;
        for i in 0..order.len() {
            match runs.last_mut() {
                Some(run) if key(run.0) == key(i) => run.1 = i + 1,
                _ => runs.push((i, i + 1)),
            }
        }
        let cells = runs.iter().map(|&(s, e)| (key(s), (s, e))).collect();
        Some(FacingGrid {
            keys,
            cell,
            order,
            runs,
            cells,
        })
    }

    /// `visit(v, candidates)` for every vertex v of the grid, by cell on the pool: the
    /// candidates are the vertices of the 27 cells around v's whose normal could face the normal
    /// of some vertex of v's cell (see [`facing_candidates`]), a superset of those that face
    /// v's within the reach. The answers come in the grid's order; each thread reuses its
    /// lists of cells and candidates from cell to cell.
    pub(crate) fn each<T: Send + Default + Clone>(
        &self,
        vertices: &[Vec3],
        normals: &[Vec3],
        visit: impl Fn(usize, &[u32]) -> T + Sync,
    ) -> Vec<T> {
        let order = &self.order;
        let mut out = vec![T::default(); order.len()];
        // Each cell's run of `order` answered into its own run of `out`.
        let mut rest = out.as_mut_slice();
        let mut runs = Vec::with_capacity(self.runs.len());
        for &(s, e) in &self.runs {
            let (run, tail) = std::mem::take(&mut rest).split_at_mut(e - s);
            runs.push((s, run));
            rest = tail;
        }
        runs.into_par_iter().for_each_init(
            || (Vec::new(), Vec::new()),
            |(near, facing), (s, answers)| {
                // The 27 cells around this one, looked up once for all its vertices.
                let c = cell_of(vertices[order[s] as u32 as usize], self.cell);
                near.clear();
                near.extend(
                    (-1..=1)
                        .flat_map(|z| (-1..=1).flat_map(move |y| (-1..=1).map(move |x| [x, y, z])))
                        .filter_map(|d| self.keys.key(c + IVec3::from_array(d)))
                        .filter_map(|k| self.cells.get(&k).copied()),
                );
                let run = &order[s..s + answers.len()];
                facing_candidates(run, near, order, normals, facing);
                for (answer, &v) in answers.iter_mut().zip(run) {
                    *answer = visit(v as u32 as usize, facing);
                }
            },
        );
        out
    }
}

/// The vertices of the cells `near` (runs of `order`) whose normals could face the normal of
/// some vertex of `run`, in the cells' order: those whose angle to the run's mean normal
/// exceeds FACING's angle less the run's spread (the largest angle of a normal of the run to
/// that mean) and a margin for rounding; all of them where the run's normals spread too far.
/// The rest cannot pass the facing test, so the nearest facing vertex is the same.
fn facing_candidates(
    run: &[u64],
    near: &[(usize, usize)],
    order: &[u64],
    normals: &[Vec3],
    facing: &mut Vec<u32>,
) {
    facing.clear();
    let all = || {
        near.iter()
            .flat_map(|&(s, e)| order[s..e].iter().map(|&u| u as u32))
    };
    let sum: Vec3 = run.iter().map(|&v| normals[v as u32 as usize]).sum();
    let mean = sum.normalize_or_zero();
    // The widest angle is the least cosine's.
    let spread = run
        .iter()
        .map(|&v| normals[v as u32 as usize])
        .filter(|n| *n != Vec3::ZERO)
        .map(|n| mean.dot(n).clamp(-1.0, 1.0))
        .fold(1.0f32, f32::min)
        .acos();
    let angle = FACING.acos() - spread - 0.01;
    if mean == Vec3::ZERO || angle <= 0.0 {
        facing.extend(all());
        return;
    }
    let most = angle.cos();
    facing.extend(all().filter(|&u| mean.dot(normals[u as usize]) < most));
}
