//! The field values of the band (Sec. 4.1), packed: each brick keeps one value per surface
//! vertex of its mask, in mask bit order, instead of all 8³. An isolated droplet's band fills
//! a small part of the bricks it touches, and a dense brick array made its memory grow with
//! the bricks (2 KiB each), not with its vertices.

use glam::IVec3;
use rayon::prelude::*;

use super::band::{BRICK_VERTICES, Band};
use crate::error::Result;
use crate::recon::budget;

/// Field values of a band's surface vertices; NaN where a vertex is not in the band.
#[derive(Debug, Default, Clone)]
pub struct BrickValues {
    /// Where each brick's values start in `values`; one more entry than bricks.
    starts: Vec<usize>,
    values: Vec<f32>,
}

impl BrickValues {
    /// Values per brick of `band`, each given as all 8³ vertices (those outside the mask are
    /// dropped) by `dense(state, brick index)`, in parallel with one `init()` state per task.
    pub fn sample<S>(
        band: &Band,
        init: impl Fn() -> S + Sync + Send,
        dense: impl Fn(&mut S, usize) -> [f32; BRICK_VERTICES] + Sync + Send,
    ) -> Result<BrickValues> {
        let (values, _) = Self::sample_with(band, init, |s, b| (dense(s, b), ()))?;
        Ok(values)
    }

    /// [`sample`](Self::sample) where `dense` also gives something else per brick: those, in
    /// brick order.
    pub fn sample_with<S, T: Send>(
        band: &Band,
        init: impl Fn() -> S + Sync + Send,
        dense: impl Fn(&mut S, usize) -> ([f32; BRICK_VERTICES], T) + Sync + Send,
    ) -> Result<(BrickValues, Vec<T>)> {
        let what = || format!("the field values of {} bricks", band.bricks.len());
        let mut starts = budget::try_vec(band.bricks.len() + 1, what)?;
        let mut total = 0usize;
        starts.push(0);
        for mask in &band.masks {
            total += mask.iter().map(|w| w.count_ones() as usize).sum::<usize>();
            starts.push(total);
        }
        let mut values = budget::try_zeroed::<f32>(total, || {
            format!("the field values of {total} band vertices")
        })?;
        let mut slices: Vec<&mut [f32]> = budget::try_vec(band.bricks.len(), what)?;
        slices.extend(brick_slices(&starts, &mut values));
        // Bricks differ in cost a hundredfold: small tasks keep both threads busy to the end.
        let extras = slices
            .into_par_iter()
            .with_max_len(TASK_BRICKS)
            .enumerate()
            .map_init(init, |state, (b, out)| {
                let (dense, extra) = dense(state, b);
                pack(&band.masks[b], &dense, out);
                extra
            })
            .collect();
        Ok((BrickValues { starts, values }, extras))
    }

    /// The value of vertex `local` of brick `b`, whose mask is `mask`; NaN outside the band.
    pub fn get(&self, mask: &[u64; 8], b: usize, local: usize) -> f32 {
        slot(mask, local).map_or(f32::NAN, |k| self.values[self.starts[b] + k])
    }

    /// The `index`th value of all, in brick order and bit order within each brick.
    #[inline]
    pub fn at(&self, index: usize) -> f32 {
        self.values[index]
    }

    /// Per brick of `band` (whose values these are) and word of its mask, the index in
    /// [`at`](Self::at) of the word's first value.
    pub fn word_starts(&self, band: &Band) -> Vec<[u32; 8]> {
        band.masks
            .iter()
            .zip(&self.starts)
            .map(|(mask, &start)| {
                let mut next = start as u32;
                mask.map(|w| {
                    let first = next;
                    next += w.count_ones();
                    first
                })
            })
            .collect()
    }

    /// Sets the values of `band`'s vertices that `sub` holds (each of them in `band`) to
    /// theirs in `sub_values`, brick by brick in parallel.
    pub fn overwrite(&mut self, band: &Band, sub: &Band, sub_values: &BrickValues) {
        brick_slices(&self.starts, &mut self.values)
            .collect::<Vec<_>>()
            .into_par_iter()
            .with_max_len(TASK_BRICKS)
            .enumerate()
            .for_each(|(b, out)| {
                let Some(j) = sub.brick_index(band.bricks[b]) else {
                    return;
                };
                let from = sub_values.brick(j);
                // Both packed in bit order: walk the band's bits, taking the sub-band's.
                let (mut k, mut n) = (0, 0);
                for (&word, &taken) in band.masks[b].iter().zip(&sub.masks[j]) {
                    debug_assert!(taken & !word == 0, "a sub-band vertex outside the band");
                    let mut bits = word;
                    while bits != 0 {
                        let bit = bits & bits.wrapping_neg();
                        if taken & bit != 0 {
                            out[k] = from[n];
                            n += 1;
                        }
                        k += 1;
                        bits &= bits - 1;
                    }
                }
            });
    }

    /// Brick `b`'s values in word `z` of its mask `mask` (the plane of local z), by bit.
    #[inline]
    pub fn plane(&self, mask: &[u64; 8], b: usize, z: usize) -> &[f32] {
        let before: usize = mask[..z].iter().map(|m| m.count_ones() as usize).sum();
        let start = self.starts[b] + before;
        &self.values[start..start + mask[z].count_ones() as usize]
    }

    /// Brick `b`'s values, in bit order of its mask.
    #[inline]
    pub fn brick(&self, b: usize) -> &[f32] {
        &self.values[self.starts[b]..self.starts[b + 1]]
    }

    /// All 8³ values of brick `b` (mask `mask`), NaN outside the band.
    pub fn dense(&self, mask: &[u64; 8], b: usize) -> [f32; BRICK_VERTICES] {
        let mut out = [f32::NAN; BRICK_VERTICES];
        let mut k = self.starts[b];
        for (z, &word) in mask.iter().enumerate() {
            let mut bits = word;
            while bits != 0 {
                let bit = bits.trailing_zeros() as usize;
                out[64 * z + bit] = self.values[k];
                k += 1;
                bits &= bits - 1;
            }
        }
        out
    }

    pub fn heap_bytes(&self) -> usize {
        self.starts.capacity() * size_of::<usize>() + self.values.capacity() * size_of::<f32>()
    }
}

/// `values` cut into each brick's values (`starts`: where each brick's values begin).
fn brick_slices<'a>(
    starts: &'a [usize],
    values: &'a mut [f32],
) -> impl Iterator<Item = &'a mut [f32]> + 'a {
    let mut rest = values;
    starts.windows(2).map(move |w| {
        let (head, tail) = std::mem::take(&mut rest).split_at_mut(w[1] - w[0]);
        rest = tail;
        head
    })
}

/// Bricks per task at most.
pub const TASK_BRICKS: usize = 16;

/// The place of vertex `local` among its brick's values, if `mask` holds it.
fn slot(mask: &[u64; 8], local: usize) -> Option<usize> {
    let (w, bit) = (local / 64, local % 64);
    if mask[w] >> bit & 1 == 0 {
        return None;
    }
    let before: u32 = mask[..w].iter().map(|m| m.count_ones()).sum();
    Some((before + (mask[w] & ((1u64 << bit) - 1)).count_ones()) as usize)
}

/// Writes the values of `dense` whose bits `mask` sets into `out`, in bit order.
fn pack(mask: &[u64; 8], dense: &[f32; BRICK_VERTICES], out: &mut [f32]) {
    let mut k = 0;
    for (z, &word) in mask.iter().enumerate() {
        let mut bits = word;
        while bits != 0 {
            let bit = bits.trailing_zeros() as usize;
            out[k] = dense[64 * z + bit];
            k += 1;
            bits &= bits - 1;
        }
    }
}

/// Adds the vertices of `other` and their values to `band` and `values`, keeping bricks in
/// (z, y, x) order; where both have a vertex, `other`'s value wins unless it is NaN.
pub fn merge(
    band: &mut Band,
    values: &mut BrickValues,
    other: Band,
    other_values: BrickValues,
) -> Result<()> {
    // Each merged brick with its index in `band` and in `other`.
    let mut sources: Vec<(IVec3, Option<usize>, Option<usize>)> = band
        .bricks
        .iter()
        .enumerate()
        .map(|(i, &b)| (b, Some(i), None))
        .collect();
    for (j, &b) in other.bricks.iter().enumerate() {
        match band.brick_index(b) {
            Some(i) => sources[i].2 = Some(j),
            None => sources.push((b, None, Some(j))),
        }
    }
    sources.sort_unstable_by_key(|(b, _, _)| (b.z, b.y, b.x));
    let masks = sources
        .iter()
        .map(|&(_, i, j)| {
            let mut mask = i.map_or([0; 8], |i| band.masks[i]);
            for (word, add) in mask.iter_mut().zip(j.map_or([0; 8], |j| other.masks[j])) {
                *word |= add;
            }
            mask
        })
        .collect();
    let bricks = sources.iter().map(|s| s.0).collect();
    let merged = Band::from_masks(band.cell, bricks, masks);
    let merged_values = BrickValues::sample(
        &merged,
        || (),
        |_, k| {
            let (_, i, j) = sources[k];
            let mut v = i.map_or([f32::NAN; BRICK_VERTICES], |i| {
                values.dense(&band.masks[i], i)
            });
            if let Some(j) = j {
                let add = other_values.dense(&other.masks[j], j);
                for (a, &x) in v.iter_mut().zip(&add) {
                    if !x.is_nan() {
                        *a = x;
                    }
                }
            }
            v
        },
    )?;
    *band = merged;
    *values = merged_values;
    Ok(())
}
