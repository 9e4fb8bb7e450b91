//! Deferred values: Marching Cubes (Sec. 4.2) reads a vertex's value only at the ends of the
//! crossed edges it meshes, and at their six neighbours for the grid normals' differences;
//! everywhere else the sign alone decides. Where the field settles its sign from cheap
//! bounds, the sampling keeps only the sign, and the values the triangulation will read are
//! sampled once the band is closed and its crossed edges are known.
//!
//! Exact by construction: every value the triangles read is the one the field gives, so the
//! mesh is the same to the bit as with every value sampled.

use glam::IVec3;
use rayon::prelude::*;

use super::field_sampling::{sample_field, sample_field_deferring};
use crate::error::Result;
use crate::field::ScalarField;
use crate::neighbours::handler_array::HandlerArray;
use crate::recon::bricks::band::{BRICK, Band, brick_of, local_index, local_vertex};
use crate::recon::bricks::brick_neighbours::NeighbourWalk;
use crate::recon::bricks::brick_values::BrickValues;
use crate::recon::bricks::edge_tables::EdgeTables;
use crate::recon::bricks::halo::neighbour_slot;

/// The vertices whose values were left out, as bits per brick, by brick coordinates (closing
/// the band renumbers the bricks).
#[derive(Clone)]
pub struct Deferred {
    bricks: Vec<(IVec3, [u64; 8])>,
}

/// Deferring pays where the lane sums keep their accumulators in registers (AVX-512's 32):
/// with AVX2's 16, SSP07's 13 sums spill to the stack, and run back to back, with no
/// eigenvalue between them, the sampling took 1.4× as long on this project's AMD EPYC
/// machines instead of 0.88×.
fn deferring_pays() -> bool {
    #[cfg(test)]
    if let Some(defer) = tests::DEFER.get() {
        return defer;
    }
    #[cfg(target_arch = "x86_64")]
    return crate::neighbours::lane_sums::lanes_path()
        == crate::neighbours::lane_sums::Lanes::Avx512;
    #[cfg(not(target_arch = "x86_64"))]
    return false;
}

impl Deferred {
    /// The field on `band`, deferring the values that the field's sign settles where that
    /// pays, with the vertices it deferred.
    pub fn sample<F: ScalarField + ?Sized>(
        band: &Band,
        handlers: &HandlerArray,
        field: &F,
    ) -> Result<(BrickValues, Deferred)> {
        if !deferring_pays() {
            let values = sample_field(band, handlers, field)?;
            return Ok((values, Deferred { bricks: Vec::new() }));
        }
        let (values, masks) = sample_field_deferring(band, handlers, field)?;
        Ok((values, Deferred::new(band, masks)))
    }

    /// From `masks`, one per brick of `band`.
    fn new(band: &Band, masks: Vec<[u64; 8]>) -> Deferred {
        Deferred {
            bricks: band
                .bricks
                .iter()
                .zip(masks)
                .filter(|(_, m)| m.iter().any(|&w| w != 0))
                .map(|(&b, m)| (b, m))
                .collect(),
        }
    }

    /// How many values were left out.
    pub fn len(&self) -> usize {
        let bits = |m: &[u64; 8]| m.iter().map(|w| w.count_ones() as usize).sum::<usize>();
        self.bricks.iter().map(|(_, m)| bits(m)).sum()
    }

    /// The vertices still left out, as bits per brick of `band` (this band, or one closing
    /// grew from it).
    pub fn masks(&self, band: &Band) -> Vec<[u64; 8]> {
        let mut masks = vec![[0u64; 8]; band.bricks.len()];
        for &(brick, mask) in &self.bricks {
            let b = band
                .brick_index(brick)
                .expect("closing a band keeps its bricks");
            masks[b] = mask;
        }
        masks
    }

    /// Samples into `values` each left-out value that the triangulation of the closed `band`
    /// with edge tables `tables` reads, and forgets it; returns how many. Called again after
    /// the band changed (the field averaged along the flow), it samples only the values
    /// newly read.
    pub fn resolve<F: ScalarField + ?Sized>(
        &mut self,
        band: &Band,
        values: &mut BrickValues,
        tables: &EdgeTables,
        handlers: &HandlerArray,
        field: &F,
    ) -> Result<usize> {
        if self.bricks.is_empty() {
            return Ok(0);
        }
        let masks = self.masks(band);
        let mut read: Vec<IVec3> = tables
            .0
            .par_iter()
            .enumerate()
            .filter_map(|(b, t)| t.as_deref().map(|t| (b, t)))
            .map_init(
                || NeighbourWalk::new(&band.bricks),
                |walk, (b, edges)| {
                    let around = walk.around(band.bricks[b]);
                    let deferred = |l: IVec3| {
                        let d = brick_of(l);
                        around[neighbour_slot(d)].is_some_and(|n| {
                            let i = local_index(l - d * BRICK);
                            masks[n][i / 64] >> (i % 64) & 1 == 1
                        })
                    };
                    let mut out = Vec::new();
                    edges.each(|local, axis| {
                        let l = local_vertex(local);
                        for end in [l, l + IVec3::AXES[axis]] {
                            for v in [end].into_iter().chain(STEPS.map(|s| end + s)) {
                                if deferred(v) {
                                    out.push(band.bricks[b] * BRICK + v);
                                }
                            }
                        }
                    });
                    out
                },
            )
            .flatten()
            .collect();
        read.par_sort_unstable_by_key(|v| (v.z, v.y, v.x));
        read.dedup();
        if read.is_empty() {
            return Ok(0);
        }
        let sub = Band::from_vertices(&read, band.cell);
        let exact = sample_field(&sub, handlers, field)?;
        values.overwrite(band, &sub, &exact);
        for (brick, mask) in &mut self.bricks {
            if let Some(j) = sub.brick_index(*brick) {
                for (word, read) in mask.iter_mut().zip(sub.masks[j]) {
                    *word &= !read;
                }
            }
        }
        Ok(read.len())
    }
}

/// The six neighbours a grid normal's central differences read.
const STEPS: [IVec3; 6] = [
    IVec3::NEG_X,
    IVec3::X,
    IVec3::NEG_Y,
    IVec3::Y,
    IVec3::NEG_Z,
    IVec3::Z,
];

#[cfg(test)]
pub(crate) mod tests {
    use std::cell::Cell;

    use glam::Vec3;

    use crate::Engine;
    use crate::config::{Normals, Params};
    use crate::tests::common::{field_params, lattice_ball, reconstruct, uniform};

    use crate::recon::stages::field_sampling::tests::MARGIN_CELLS;

    thread_local! {
        /// Whether the band's sampling defers (on any CPU), where a test says so.
        pub static DEFER: Cell<Option<bool>> = const { Cell::new(None) };
    }

    /// A wavy blob with a tail of drops, some lone and some in pairs: surfaces of every
    /// curvature the SSP07 bounds see.
    fn splashy_blob(r: f32) -> Vec<Vec3> {
        let mut next = uniform(7);
        let mut ps: Vec<Vec3> = lattice_ball(Vec3::ZERO, 6.0 * r, r)
            .into_iter()
            .filter(|p| p.x + 0.5 * (p.y * 40.0).sin() * r < 4.0 * r)
            .map(|p| p + crate::tests::common::uniform_point(&mut next) * 0.2 * r)
            .collect();
        ps.extend((0..30).map(|i| {
            let a = i as f32 * 0.9;
            Vec3::new(8.0 + i as f32 * 0.8, a.sin() * 3.0, a.cos() * 3.0) * r
        }));
        ps
    }

    #[test]
    fn deferring_values_keeps_the_mesh_to_the_bit() {
        let r = 0.01;
        let ps = splashy_blob(r);
        for (cell, normals) in [
            ("r/2", Normals::Field),
            ("r/2", Normals::Grid),
            ("r", Normals::Field),
            ("r/3", Normals::Grid),
        ] {
            let params = Params {
                normals,
                ..field_params("ssp07", r, cell)
            };
            let run = |defer: bool, margin: Option<f32>| {
                DEFER.set(Some(defer));
                MARGIN_CELLS.set(margin);
                let out = reconstruct(&ps, &params, Engine::NarrowBand);
                DEFER.set(None);
                MARGIN_CELLS.set(None);
                out.unwrap()
            };
            let all = run(false, None);
            assert_eq!(all.stats.deferred_values, 0);
            assert!(!all.mesh.triangles.is_empty());
            let bits = |v: &[Vec3]| {
                v.iter()
                    .map(|p| p.to_array().map(f32::to_bits))
                    .collect::<Vec<_>>()
            };
            // The default margin, and none at all: then most deferred values are read.
            for margin in [None, Some(0.0)] {
                let what = format!("cell {cell}, {normals:?} normals, margin {margin:?}");
                let deferred = run(true, margin);
                let (a, b) = (&deferred.mesh, &all.mesh);
                assert!(a.triangles == b.triangles, "{what}: the triangles differ");
                assert!(bits(&a.vertices) == bits(&b.vertices), "{what}: vertices");
                assert!(bits(&a.normals) == bits(&b.normals), "{what}: normals");
                let share =
                    deferred.stats.deferred_values as f32 / deferred.stats.surface_vertices as f32;
                assert!(share > 0.05, "{what}: {share} of the values deferred");
            }
        }
    }
}
