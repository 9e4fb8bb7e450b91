//! The fluid's own motion between frames (issue 38): each particle's displacement to a
//! neighbouring frame, matched by its identity (SPlisHSPlasH's `id`) or else its velocity × Δt,
//! and the kernel mean of the displacements around a point — the motion a free surface follows
//! (the kinematic condition).

use std::collections::BTreeMap;

use glam::Vec3;
use rayon::prelude::*;
use rustc_hash::FxHashMap;

use crate::attribute_names;
use crate::attributes::interpolate;
use crate::error::{Error, Result};
use crate::field::radial_kernel::RadialKernel;
use crate::io::Attribute;

/// Ids are read as `f32` attributes: exact integers up to 2^24.
const LARGEST_ID: f32 = (1 << 24) as f32;

/// A frame's particles with what carries them to the neighbouring frames.
#[derive(Debug, Clone, Default)]
pub struct FrameMotion {
    /// Positions, as read.
    pub positions: Vec<Vec3>,
    /// Each particle's identity across frames, where the file has unique integer ids.
    pub ids: Option<Vec<u32>>,
    /// Velocities, where the file has them.
    pub velocities: Option<Vec<Vec3>>,
}

impl FrameMotion {
    /// The positions with copies of the `id` and `velocity` attributes (any spelling of the
    /// alias table) of `attributes`, which keeps them under their canonical names. Ids that
    /// are not unique integers in [0, 2^24) are not used (the reason is returned, for a
    /// warning); non-finite velocities neither.
    pub fn new(
        positions: Vec<Vec3>,
        attributes: &mut BTreeMap<String, Attribute>,
    ) -> (FrameMotion, Option<String>) {
        let mut why = None;
        let mut copy = |name: &str| {
            let a = attribute_names::take(attributes, name)?;
            attributes.insert(name.to_string(), a.clone());
            Some(a)
        };
        let ids = match copy("id") {
            Some(Attribute::Scalar(ids)) => match exact_ids(&ids) {
                Ok(ids) => Some(ids),
                Err(e) => {
                    why = Some(e);
                    None
                }
            },
            _ => None,
        };
        let velocities = match copy("velocity") {
            Some(Attribute::Vector(v)) if v.iter().all(|v| v.is_finite()) => Some(v),
            _ => None,
        };
        (
            FrameMotion {
                positions,
                ids,
                velocities,
            },
            why,
        )
    }

    /// Positions with their particles' `ids` (as a caller holding frames in memory has them);
    /// [`Error::Input`] when the counts differ or an id repeats.
    pub fn with_ids(positions: Vec<Vec3>, ids: Vec<u32>) -> Result<FrameMotion> {
        if ids.len() != positions.len() {
            return Err(Error::input(format!(
                "{} ids for {} particles",
                ids.len(),
                positions.len()
            )));
        }
        if let Some(id) = repeated(&ids) {
            return Err(Error::input(format!("particle id {id} appears twice")));
        }
        Ok(FrameMotion {
            positions,
            ids: Some(ids),
            velocities: None,
        })
    }

    /// The displacement of each of this frame's particles to frame `other`, `steps` frames
    /// later (negative: earlier): matched by id where both frames have ids (None for a
    /// particle `other` lacks), else `steps` × `frame_time` × the velocity where this frame
    /// has velocities and the frame time is known; None when neither.
    pub fn displacements(
        &self,
        other: &FrameMotion,
        steps: i32,
        frame_time: Option<f32>,
    ) -> Option<Vec<Option<Vec3>>> {
        if let (Some(ids), Some(other_ids)) = (&self.ids, &other.ids) {
            let at = IdIndex::new(other_ids);
            return Some(
                ids.par_iter()
                    .zip(&self.positions)
                    .map(|(&id, p)| at.get(id).map(|j| other.positions[j as usize] - *p))
                    .collect(),
            );
        }
        let (velocities, dt) = (self.velocities.as_ref()?, frame_time?);
        let scale = steps as f32 * dt;
        Some(velocities.iter().map(|v| Some(*v * scale)).collect())
    }
}

/// Where each id sits in a frame: a table indexed by id where the largest id is at most a few
/// times the particle count (SPlisHSPlasH numbers its particles from 0), else a hash map.
enum IdIndex {
    Table(Vec<u32>),
    Map(FxHashMap<u32, u32>),
}

impl IdIndex {
    fn new(ids: &[u32]) -> IdIndex {
        if let Some(largest) = dense_largest(ids) {
            let mut table = vec![u32::MAX; largest + 1];
            for (i, &id) in ids.iter().enumerate() {
                table[id as usize] = i as u32;
            }
            IdIndex::Table(table)
        } else {
            IdIndex::Map(
                ids.iter()
                    .enumerate()
                    .map(|(i, &id)| (id, i as u32))
                    .collect(),
            )
        }
    }

    fn get(&self, id: u32) -> Option<u32> {
        match self {
            IdIndex::Table(t) => t.get(id as usize).copied().filter(|&i| i != u32::MAX),
            IdIndex::Map(m) => m.get(&id).copied(),
        }
    }
}

/// The largest of `ids` where it is at most a few times their count (a table by id then
/// costs memory like the ids themselves), else None.
fn dense_largest(ids: &[u32]) -> Option<usize> {
    let largest = ids.iter().copied().max().unwrap_or(0) as usize;
    (largest < 4 * ids.len() + 1024).then_some(largest)
}

/// Unique integer ids, or why not.
fn exact_ids(ids: &[f32]) -> std::result::Result<Vec<u32>, String> {
    if let Some(bad) = ids
        .iter()
        .find(|&&id| !((0.0..LARGEST_ID).contains(&id) && id.fract() == 0.0))
    {
        return Err(format!(
            "particle ids must be integers from 0 to 2^24 (read as 32-bit floats); found {bad}"
        ));
    }
    let ids: Vec<u32> = ids.iter().map(|&id| id as u32).collect();
    if let Some(id) = repeated(&ids) {
        return Err(format!("particle id {id} appears twice"));
    }
    Ok(ids)
}

/// The least id that appears more than once in `ids`, if any: marked off in a bit per id
/// where the ids are numbered densely (as [`IdIndex`] takes them), else found by sorting.
fn repeated(ids: &[u32]) -> Option<u32> {
    if let Some(largest) = dense_largest(ids) {
        let mut seen = vec![0u64; largest / 64 + 1];
        let mut least = None;
        for &id in ids {
            let (w, bit) = (id as usize / 64, 1u64 << (id % 64));
            if seen[w] & bit != 0 {
                least = Some(least.map_or(id, |l: u32| l.min(id)));
            }
            seen[w] |= bit;
        }
        return least;
    }
    let mut sorted = ids.to_vec();
    sorted.sort_unstable();
    sorted.windows(2).find(|w| w[0] == w[1]).map(|w| w[0])
}

/// The cubic-spline mean (support `support`, Shepard-normalised) of each of the displacements
/// `moves` of `particles` at every point; None where no matched particle is within reach (a
/// vertex of a cavity's wall more than 2r from every particle: its motion is unknown, and
/// taking it as zero would read the fluid's motion there as the surface's own). `cell`: the
/// points' spacing, as for attribute interpolation. In one pass over the particles when the
/// same particles are matched in all (a sequence whose frames keep their particles), else one
/// pass each.
pub fn mean_motions(
    points: &[Vec3],
    particles: &[Vec3],
    moves: &[&[Option<Vec3>]],
    support: f32,
    cell: f32,
) -> Result<Vec<Vec<Option<Vec3>>>> {
    let first = moves.first().copied().unwrap_or_default();
    let same = |m: &[Option<Vec3>]| m.iter().zip(first).all(|(a, b)| a.is_some() == b.is_some());
    if !moves.iter().all(|m| same(m)) {
        return moves
            .iter()
            .map(|m| Ok(mean_motions(points, particles, &[m], support, cell)?.remove(0)))
            .collect();
    }
    let at: Vec<Vec3> = particles
        .iter()
        .zip(first)
        .filter(|(_, m)| m.is_some())
        .map(|(p, _)| *p)
        .collect();
    let mut channels: Vec<Attribute> = moves
        .iter()
        .map(|m| Attribute::Vector(m.iter().flatten().copied().collect()))
        .collect();
    // The Shepard mean of ones is 1 wherever a particle weighs, 0 elsewhere.
    channels.push(Attribute::Scalar(vec![1.0; at.len()]));
    let kernel = RadialKernel::CubicSpline { support };
    let refs: Vec<&Attribute> = channels.iter().collect();
    let mut out = interpolate(points, &at, &refs, &kernel, cell)?;
    let Some(Attribute::Scalar(weighed)) = out.pop() else {
        unreachable!("the ones come out last, as a scalar")
    };
    Ok(out
        .into_iter()
        .map(|a| match a {
            Attribute::Vector(v) => v
                .into_iter()
                .zip(&weighed)
                .map(|(v, &w)| (w > 0.5).then_some(v))
                .collect(),
            Attribute::Scalar(_) => unreachable!("displacements are vectors"),
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::{FrameMotion, repeated};

    /// Ids numbered densely (a table) and sparsely (a hash map) match the same particles, and
    /// the least repeated id is the one named either way.
    #[test]
    fn ids_match_dense_or_sparse() {
        for scale in [1u32, 1 << 20] {
            let ids: Vec<u32> = (0..50u32).map(|i| ((i * 7) % 50) * scale).collect();
            let at = |i: u32| Vec3::splat((i / scale) as f32);
            let positions: Vec<Vec3> = ids.iter().map(|&i| at(i)).collect();
            let later: Vec<u32> = ids
                .iter()
                .rev()
                .copied()
                .filter(|&i| i != 3 * scale)
                .collect();
            let moved: Vec<Vec3> = later.iter().map(|&i| at(i) + Vec3::ONE).collect();
            let a = FrameMotion::with_ids(positions, ids.clone()).unwrap();
            let b = FrameMotion::with_ids(moved, later).unwrap();
            let d = a.displacements(&b, 1, None).unwrap();
            for (id, d) in ids.iter().zip(&d) {
                let want = (*id != 3 * scale).then_some(Vec3::ONE);
                assert_eq!(*d, want, "id {id}");
            }
            let mut twice = ids.clone();
            twice.extend([9 * scale, 4 * scale]);
            assert_eq!(repeated(&twice), Some(4 * scale));
            assert_eq!(repeated(&ids), None);
        }
    }
}
