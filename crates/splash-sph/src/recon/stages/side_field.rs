//! A frame beside the one reconstructed, read where the fluid carries frame t's vertices
//! (`flow_mean`): its values as its own sampling left them on its closed band, trilinearly
//! interpolated between the grid vertices around each carried place.

use glam::{DVec3, IVec3, Vec3};

use crate::neighbours::handler_array::HandlerArray;
use crate::recon::bricks::band::{BRICK, Band, brick_of, local_index};
use crate::recon::bricks::brick_values::BrickValues;

/// A frame beside the one reconstructed, as its own reconstruction sampled it: its closed
/// band's values, and the handler array to sample the vertices it left out or never reached.
#[derive(Clone, Copy)]
pub(crate) struct SideField<'a> {
    pub band: &'a Band,
    pub values: &'a BrickValues,
    /// Per brick of `band`, the vertices it holds a value for (not left out).
    pub known: &'a [[u64; 8]],
    /// Per brick of `band` and word of its mask, where its values start in `values`.
    pub word_starts: &'a [[u32; 8]],
    pub handlers: &'a HandlerArray,
}

/// A corner of a carried vertex's cell that a side's own sampling gave no value.
pub(super) struct Miss {
    /// The vertex's place in its brick's list, the side, and the corner's weight there.
    pub vertex: u32,
    pub side: u8,
    pub weight: f32,
    pub corner: IVec3,
}

/// Values of a [`SideField`] looked up vertex by vertex, the last brick's index kept (the
/// corners of a vertex's cell and of its neighbours' mostly share a brick).
pub(super) struct Lookup<'a> {
    side: &'a SideField<'a>,
    last: Option<(IVec3, Option<usize>)>,
}

impl<'a> Lookup<'a> {
    pub fn new(side: &'a SideField<'a>) -> Self {
        Lookup { side, last: None }
    }

    /// The side's value at vertex `v`, if its own sampling gave it one.
    #[inline]
    pub fn value(&mut self, v: IVec3) -> Option<f32> {
        let brick = brick_of(v);
        let b = match self.last {
            Some((last, b)) if last == brick => b,
            _ => {
                let b = self.side.band.brick_index(brick);
                self.last = Some((brick, b));
                b
            }
        }?;
        let i = local_index(v - brick * BRICK);
        let (word, bit) = (i / 64, i % 64);
        let side = self.side;
        if side.known[b][word] >> bit & 1 == 0 {
            return None;
        }
        let below = side.band.masks[b][word] & ((1u64 << bit) - 1);
        Some(
            side.values
                .at(side.word_starts[b][word] as usize + below.count_ones() as usize),
        )
    }
}

/// The eight corners of a cell, in the order of [`corner_weights`].
pub(super) const CORNERS: [IVec3; 8] = [
    IVec3::new(0, 0, 0),
    IVec3::new(1, 0, 0),
    IVec3::new(0, 1, 0),
    IVec3::new(1, 1, 0),
    IVec3::new(0, 0, 1),
    IVec3::new(1, 0, 1),
    IVec3::new(0, 1, 1),
    IVec3::new(1, 1, 1),
];

/// The grid cell (its lowest vertex) holding vertex `v` moved by `m`, and where in it (0 to 1
/// on each axis); a vertex that does not move is its own cell's corner, exactly.
pub(super) fn cell_of_carried(v: IVec3, m: Vec3, cell: f32) -> (IVec3, Vec3) {
    if m == Vec3::ZERO {
        return (v, Vec3::ZERO);
    }
    let g = v.as_dvec3() + m.as_dvec3() / f64::from(cell);
    // ⌊g⌋ without a call to libm's floor per coordinate (as `neighbours::cell_of`).
    let floor = |x: f64| {
        let t = x as i64;
        (t - i64::from(t as f64 > x)) as f64
    };
    let c = DVec3::new(floor(g.x), floor(g.y), floor(g.z));
    (c.as_ivec3(), (g - c).as_vec3())
}

/// Trilinear weights of the [`CORNERS`] at `f` within a cell.
pub(super) fn corner_weights(f: Vec3) -> [f32; 8] {
    let g = Vec3::ONE - f;
    CORNERS.map(|o| {
        let x = if o.x == 1 { f.x } else { g.x };
        let y = if o.y == 1 { f.y } else { g.y };
        let z = if o.z == 1 { f.z } else { g.z };
        x * y * z
    })
}

/// The value `values` holds at vertex `v` of `band`, which holds it.
pub(super) fn value_at(band: &Band, values: &BrickValues, v: IVec3) -> f32 {
    let brick = brick_of(v);
    let b = band.brick_index(brick).expect("a sampled corner's brick");
    values.get(&band.masks[b], b, local_index(v - brick * BRICK))
}
