//! Marching Cubes on random fields: whatever the corner signs, including every ambiguous face,
//! the triangulation of a region whose border is outside is closed, manifold and oriented.

use crate::mesh::topology::{signed_volume, topology};
use crate::recon::bricks::band::{BRICK, BRICK_VERTICES, Band, local_index};
use crate::recon::bricks::brick_signs::Signs;
use crate::recon::bricks::brick_values::BrickValues;
use crate::recon::bricks::edge_tables::EdgeTables;
use crate::recon::stages::triangulation::triangulate;
use glam::{IVec3, Vec3};

fn random_field(n: i32, seed: u64) -> (Band, BrickValues) {
    let cell = 0.1;
    // Vertices 0..=n on each axis; the half-cell margin keeps rounding off the box's edge.
    let band = Band::full(
        Vec3::ZERO,
        Vec3::splat(n as f32 * cell + 0.5 * cell),
        cell,
        0.0,
    )
    .unwrap();
    let mut uniform = crate::tests::common::uniform(seed);
    let mut next = move || uniform() - 0.5;
    let mut dense = vec![[f32::NAN; BRICK_VERTICES]; band.bricks.len()];
    for (b, &brick) in band.bricks.iter().enumerate() {
        for i in 0..BRICK_VERTICES as i32 {
            let l = IVec3::new(i % BRICK, i / BRICK % BRICK, i / (BRICK * BRICK));
            let v = brick * BRICK + l;
            if band.masks[b][l.z as usize] >> (local_index(l) % 64) & 1 == 0 {
                continue;
            }
            let border = v.min_element() == 0 || v.max_element() == n;
            dense[b][local_index(l)] = if border { 1.0 } else { next() };
        }
    }
    let values = BrickValues::sample(&band, || (), |_, b| dense[b]).unwrap();
    (band, values)
}

#[test]
fn random_fields_give_closed_oriented_surfaces() {
    for (n, seed) in [(5, 1), (10, 2), (14, 3), (20, 4), (9, 5)] {
        let (band, values) = random_field(n, seed);
        let signs = Signs::of(&band, &values);
        let tables = EdgeTables::of(&band, &signs);
        let t = triangulate(&band, &values, signs, tables, |_| Ok(())).unwrap();
        let topo = topology(&t.mesh);
        assert!(topo.triangles > 100, "n {n}: {topo:?}");
        assert!(topo.is_closed_manifold(), "n {n}: {topo:?}");
        assert_eq!(topo.unused_vertices, 0, "n {n}");
        // Every inside region is wrapped outward, so the enclosed volume is positive.
        assert!(signed_volume(&t.mesh) > 0.0, "n {n}");
    }
}
