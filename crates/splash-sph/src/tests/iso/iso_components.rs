//! Seeds and surface following against brute force: a full-grid Marching Cubes of the same
//! interpolant on the same virtual grid (every node of the particles' box evaluated) finds the
//! same crossed cells, hence the same connected components, on random and real data.

use std::collections::BTreeMap;

use glam::{IVec3, Vec3};
use rustc_hash::FxHashSet;

use crate::io::{Attribute, read_particles};
use crate::iso::quantity::{Derived, IsoRequest, interpolant};
use crate::iso::seed_cells::seed_cells;
use crate::iso::sph_interpolant::Interpolant;
use crate::iso::surface_following::{Following, case_of, follow};
use crate::iso::virtual_grid::VirtualGrid;
use crate::mesh::marching_cubes::corner_offset;
use crate::tests::common::{Jitter, fixture};

/// Crossed cells of the full grid over the particles' box widened by the support.
fn full_grid(it: &Interpolant, grid: &VirtualGrid, run: &Following) -> FxHashSet<IVec3> {
    let h = &it.handlers;
    let (lo, hi) = h
        .positions
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, u), &p| {
            (l.min(p), u.max(p))
        });
    let reach = h.cell_size();
    let to_cell = |x: Vec3| (x.as_dvec3() / grid.cell).floor().as_ivec3();
    let (a, b) = (to_cell(lo - reach) - 1, to_cell(hi + reach) + 1);
    let size = b - a + 2;
    let index = |n: IVec3| {
        let d = n - a;
        (d.x + size.x * (d.y + size.y * d.z)) as usize
    };
    let mut nodes = vec![(0.0f64, 0.0f64); (size.x * size.y * size.z) as usize];
    for z in a.z..b.z + 2 {
        for y in a.y..b.y + 2 {
            for x in a.x..b.x + 2 {
                let n = IVec3::new(x, y, z);
                let s = it.sample(grid.node(n), it.channels.value);
                nodes[index(n)] = (s.value - run.level, s.weight);
            }
        }
    }
    let mut crossed = FxHashSet::default();
    for z in a.z..=b.z {
        for y in a.y..=b.y {
            for x in a.x..=b.x {
                let cell = IVec3::new(x, y, z);
                let corners: [(f64, f64); 8] = std::array::from_fn(|c| {
                    let [i, j, k] = corner_offset(c);
                    nodes[index(cell + IVec3::new(i as i32, j as i32, k as i32))]
                });
                if corners.iter().any(|c| c.1 < run.node_threshold) {
                    continue;
                }
                let case = case_of(&corners.map(|c| c.0));
                if case != 0 && case != 255 {
                    crossed.insert(cell);
                }
            }
        }
    }
    crossed
}

/// Connected components of `cells` under face adjacency.
fn components(cells: &FxHashSet<IVec3>) -> usize {
    let mut seen = FxHashSet::default();
    let mut count = 0;
    let mut sorted: Vec<IVec3> = cells.iter().copied().collect();
    sorted.sort_unstable_by_key(|c| [c.z, c.y, c.x]);
    for &start in &sorted {
        if !seen.insert(start) {
            continue;
        }
        count += 1;
        let mut stack = vec![start];
        while let Some(c) = stack.pop() {
            for d in [
                IVec3::X,
                IVec3::Y,
                IVec3::Z,
                -IVec3::X,
                -IVec3::Y,
                -IVec3::Z,
            ] {
                let n = c + d;
                if cells.contains(&n) && seen.insert(n) {
                    stack.push(n);
                }
            }
        }
    }
    count
}

/// Follows the isosurface of `request` and compares with the full grid; returns the
/// components.
fn compare(
    positions: &[Vec3],
    mut attributes: BTreeMap<String, Attribute>,
    request: &IsoRequest,
    support: f32,
    cell: f32,
    shepard: bool,
    reach: f32,
) -> usize {
    let it = interpolant(
        positions,
        &mut attributes,
        request,
        &[],
        support,
        1.0,
        shepard,
    )
    .unwrap();
    let (lo, hi) = positions
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, u), &p| {
            (l.min(p), u.max(p))
        });
    let grid = VirtualGrid::new(cell, lo, hi, support).unwrap();
    let run = Following {
        level: f64::from(request.level),
        node_threshold: 0.1,
        cache_slices: 3,
        max_cells: u64::MAX,
    };
    let seeds = seed_cells(&it, &grid, run.level, reach);
    let followed = follow(&it, &grid, &seeds, &run).unwrap();
    let found: FxHashSet<IVec3> = followed.cells.iter().map(|c| c.cell).collect();
    let brute = full_grid(&it, &grid, &run);
    let (nf, nb) = (components(&found), components(&brute));
    let missed = brute.difference(&found).count();
    assert_eq!(
        nf, nb,
        "components: followed {nf}, full grid {nb}; {missed} cells missed"
    );
    assert_eq!(found, brute, "{missed} crossed cells missed");
    assert!(
        followed.cache.hit_ratio() > 0.5,
        "{}",
        followed.cache.hit_ratio()
    );
    nb
}

#[test]
fn random_data_every_component_is_found() {
    let r = 0.1;
    let mut jitter = Jitter::new(7);
    let mut positions = Vec::new();
    let mut a = Vec::new();
    for z in 0..14 {
        for y in 0..14 {
            for x in 0..14 {
                let p = Vec3::new(x as f32, y as f32, z as f32) * r + jitter.vec3() * (0.3 * r);
                positions.push(p);
                // A smooth wave plus noise: many small components around the level 0.
                a.push((p.x * 7.0).sin() * (p.y * 5.0).cos() + 0.8 * jitter.next());
            }
        }
    }
    for shepard in [false, true] {
        let attributes = BTreeMap::from([("a".to_string(), Attribute::Scalar(a.clone()))]);
        let request = IsoRequest {
            attribute: "a".into(),
            derived: Derived::Value,
            level: 0.0,
        };
        let n = compare(
            &positions,
            attributes,
            &request,
            2.0 * r,
            0.5 * r,
            shepard,
            1.0,
        );
        assert!(n > 3, "{n} components");
    }
}

#[test]
fn real_frame_density_and_speed_every_component_is_found() {
    let frame = read_particles(&fixture("frame_0040.ply"), None).unwrap();
    let r = 0.014;
    for (name, derived, level) in [
        ("density", Derived::Value, 1000.0),
        ("velocity", Derived::Magnitude, 1.0),
    ] {
        let request = IsoRequest {
            attribute: name.into(),
            derived,
            level,
        };
        let n = compare(
            &frame.positions,
            frame.attributes.clone(),
            &request,
            2.0 * r,
            r,
            true,
            1.0,
        );
        assert!(n >= 1, "{name}: {n} components");
    }
}
