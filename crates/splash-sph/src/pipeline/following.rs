//! A sequence whose surfaces follow the fluid (`post.temporal`, issue 38): frame t's field is
//! averaged with those of the frames beside it where the fluid carries each vertex
//! (`recon/stages/flow_mean`), and its post-processed surface is moved towards its
//! neighbours' surfaces carried to its time ([`follow_carried`]). A frame's neighbours are
//! reconstructed too, also where another job writes them (`--shard`) or their output exists
//! (`skip_existing`), so that every job writes the bytes one run over the whole sequence
//! writes. Each frame's field is sampled once, for its own surface and the means of both
//! frames beside it, while the frame two before it is reconstructed (on the same threads: each
//! fills what the other leaves idle). At most six frames' particles (t−2 … t+3), four frames'
//! sampled fields (t … t+3) and three prepared frames are held at once, with their triangles
//! binned for distance queries (each frame's once, for both frames beside it), and one file
//! read ahead while the last mesh is written, as frames meshed alone are. A frame without both
//! neighbours (the ends of the selection, a gap in its frame numbers, a neighbour that fails
//! or has no particles, particles that cannot be matched) is meshed from its own field and
//! post-processed alone, with a warning.

use std::collections::btree_map::Entry;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use super::frame::{Prepared, Ready, Staged};
use super::overlap::{Reads, run_overlapped};
use super::{FramePipeline, Plan, Progress, RunReport};
use crate::error::{Error, Result};
use crate::frames::path_frame_number;
use crate::mesh::SurfaceBins;
use crate::recon::{Sampled, Sides};
use crate::temporal::{carry, follow_carried, neighbour_bins};

/// Runs the plan's frames of the selection `inputs`, each following the fluid from its
/// neighbours, the next file read and the last mesh written on threads of their own
/// ([`run_overlapped`]); see the module's header.
pub(super) fn run_following(
    inputs: &[PathBuf],
    plan: Plan,
    fail_fast: bool,
    progress: &mut dyn Progress,
    pipeline: &mut FramePipeline,
) -> RunReport {
    if let Some(why) = pipeline.flow_mean_missing() {
        let message = format!(
            "the fields are not averaged along the flow with {why}: each frame's surface \
             follows its neighbours' alone"
        );
        progress.warning(None, &message);
    }
    let selection = Selection::new(inputs);
    let reading: Vec<PathBuf> = read_order(&plan.positions, inputs.len())
        .into_iter()
        .map(|j| inputs[j].clone())
        .collect();
    // The frames' positions in the selection, in the order the plan takes them.
    let mut positions = plan.positions.clone().into_iter();
    // Frames read, by position in the selection: their particles, for their own surface and
    // as the sides of the fields beside them.
    let mut staged: BTreeMap<usize, Result<Staged>> = BTreeMap::new();
    // Frames prepared, by position in the selection.
    let mut held: BTreeMap<usize, Result<Ready>> = BTreeMap::new();
    // Their triangles binned as neighbours, each once for both frames beside it.
    let mut bins: BTreeMap<usize, SurfaceBins> = BTreeMap::new();
    // Frames' fields sampled, by position: each frame's surface is made from its own, and the
    // frames beside it read it for their means along the flow (None: not sampled so).
    let mut fields: BTreeMap<usize, Option<Sampled>> = BTreeMap::new();
    let make = |pipeline: &mut FramePipeline,
                _: &Path,
                reads: &mut dyn Reads,
                progress: &mut dyn Progress| {
        let at = positions.next().expect("one position per frame to do");
        staged.retain(|&j, _| staged_kept(j, at));
        held.retain(|&j, _| kept(j, at));
        bins.retain(|&j, _| kept(j, at));
        fields.retain(|&j, _| j >= at);
        for j in near(at, inputs.len()) {
            if held.contains_key(&j) {
                continue;
            }
            for i in needs(j, inputs.len()) {
                if let Entry::Vacant(slot) = staged.entry(i) {
                    let read = reads.next();
                    slot.insert(
                        read.and_then(|loaded| pipeline.stage(&inputs[i], loaded, progress)),
                    );
                }
            }
            let prepared = prepare(pipeline, &selection, j, &mut staged, &mut fields, progress);
            held.insert(j, prepared);
        }
        // The frame's own error stays its outcome; its neighbours keep only its message.
        match held.remove(&at).expect("prepared above") {
            Ok(Ready::Surface(p)) => {
                let mesh = follow(pipeline, &selection, at, &p, &held, &mut bins, progress);
                let made = pipeline.finish(&p, mesh);
                held.insert(at, Ok(Ready::Surface(p)));
                made
            }
            Ok(Ready::Made(made)) => {
                let why = format!("'{}' has no particles", inputs[at].display());
                held.insert(at, Err(Error::input(why)));
                Ok(made)
            }
            Err(e) => {
                held.insert(at, Err(Error::input(e.to_string())));
                Err(e)
            }
        }
    };
    run_overlapped(plan, fail_fast, progress, pipeline, &reading, make)
}

/// Frame `j`'s surface from its particles in `staged`, its field averaged along the flow with
/// the frames beside it where both are there and can be matched (else its own field alone);
/// the fields it needs are sampled into `fields` where they are not there yet.
fn prepare(
    pipeline: &mut FramePipeline,
    selection: &Selection,
    j: usize,
    staged: &mut BTreeMap<usize, Result<Staged>>,
    fields: &mut BTreeMap<usize, Option<Sampled>>,
    progress: &mut dyn Progress,
) -> Result<Ready> {
    let input = &selection.inputs[j];
    if !matches!(staged.get(&j), Some(Ok(Staged::Particles(_)))) {
        // The frame's own outcome; frames beside it see only that it has no particles.
        let why = Error::input(format!("'{}' has no particles", input.display()));
        return match staged
            .insert(j, Err(why))
            .expect("staged before it is prepared")
        {
            Ok(Staged::Made(made)) => Ok(Ready::Made(*made)),
            Ok(Staged::Particles(_)) => unreachable!("matched above"),
            Err(e) => Err(e),
        };
    }
    let beside = |i: Option<usize>| {
        i.filter(|&i| i < selection.inputs.len() && !selection.gap_between(j, i))
            .filter(|i| matches!(staged.get(i), Some(Ok(Staged::Particles(_)))))
    };
    let sides = beside(j.checked_sub(1)).zip(beside(Some(j + 1)));
    // A field that fails to sample is left out here; its frame reports the error itself.
    let needed = [Some(j), sides.map(|s| s.0), sides.map(|s| s.1)];
    for i in needed.into_iter().flatten() {
        if let (Entry::Vacant(slot), Some(Ok(Staged::Particles(p)))) =
            (fields.entry(i), staged.get(&i))
        {
            slot.insert(
                pipeline
                    .sample(&selection.inputs[i], p, progress)
                    .ok()
                    .flatten(),
            );
        }
    }
    let particles = |i: usize| match staged.get(&i) {
        Some(Ok(Staged::Particles(p))) => p,
        _ => unreachable!("checked above"),
    };
    let own = particles(j);
    let frame_time = pipeline.frame_time();
    let moves = sides.and_then(|(before, after)| {
        let fields = [
            fields.get(&before)?.as_ref()?,
            fields.get(&after)?.as_ref()?,
        ];
        let back = own
            .motion
            .displacements(&particles(before).motion, -1, frame_time)?;
        let ahead = own
            .motion
            .displacements(&particles(after).motion, 1, frame_time)?;
        Some((fields, [back, ahead]))
    });
    let sides = moves.as_ref().map(|(fields, [back, ahead])| Sides {
        fields: *fields,
        moves: [back, ahead],
    });
    let own_field = fields.get(&j).and_then(Option::as_ref);
    // The field two frames on is sampled meanwhile, ready for the next frame's mean.
    let ahead = j + 2;
    let later = match staged.get(&ahead) {
        Some(Ok(Staged::Particles(p))) if !fields.contains_key(&ahead) => Some(p),
        _ => None,
    };
    let own_fields = (own_field, sides.as_ref());
    let (ready, sampled) = pipeline.reconstruct_sampling(input, own, own_fields, later, progress);
    if later.is_some() {
        fields.insert(ahead, sampled);
    }
    ready
}

/// The frames of the selection that making frame `at` needs prepared: it and those beside it.
fn near(at: usize, frames: usize) -> std::ops::Range<usize> {
    at.saturating_sub(1)..(at + 2).min(frames)
}

/// The frames whose particles preparing frame `j` needs: it, those beside it, and the frame
/// two on, whose field is sampled meanwhile.
fn needs(j: usize, frames: usize) -> impl Iterator<Item = usize> {
    near(j, frames).chain(Some(j + 2).filter(|&i| i < frames))
}

/// Whether frame `j` is still held prepared when frame `at` is made (frames are made in order).
fn kept(j: usize, at: usize) -> bool {
    j + 1 >= at
}

/// Whether frame `j`'s particles are still held when frame `at` is made: the frames prepared
/// then need those beside them.
fn staged_kept(j: usize, at: usize) -> bool {
    j + 2 >= at
}

/// The frames read, in order, to make the frames at `positions` of a selection of `frames`:
/// each the first time a frame prepared needs it while it is not held.
fn read_order(positions: &[usize], frames: usize) -> Vec<usize> {
    let (mut staged, mut held) = (BTreeSet::new(), BTreeSet::new());
    let mut order = Vec::new();
    for &at in positions {
        staged.retain(|&j| staged_kept(j, at));
        held.retain(|&j| kept(j, at));
        for j in near(at, frames) {
            if held.insert(j) {
                order.extend(needs(j, frames).filter(|&i| staged.insert(i)));
            }
        }
    }
    order
}

/// Frame `at`'s surface moved towards its neighbours', or its own where it cannot follow them
/// (told as a warning).
fn follow(
    pipeline: &FramePipeline,
    selection: &Selection,
    at: usize,
    own: &Prepared,
    held: &BTreeMap<usize, Result<Ready>>,
    bins: &mut BTreeMap<usize, SurfaceBins>,
    progress: &mut dyn Progress,
) -> crate::mesh::TriMesh {
    let inputs = selection.inputs;
    let neighbour = |j: Option<usize>, side: &str| -> std::result::Result<&Prepared, String> {
        let Some(j) = j.filter(|&j| j < inputs.len()) else {
            return Err(format!("no frame {side} it in the sequence"));
        };
        if selection.gap_between(at, j) {
            return Err(format!("a gap in the frame numbers {side} it"));
        }
        match held.get(&j) {
            Some(Ok(Ready::Surface(p))) => Ok(p),
            Some(Ok(Ready::Made(_))) => Err(format!(
                "the frame {side} it, '{}', has no particles",
                inputs[j].display()
            )),
            Some(Err(e)) => Err(format!("the frame {side} it failed: {e}")),
            None => unreachable!("neighbours are prepared before the frame"),
        }
    };
    let (spacing, cell) = own.grid();
    let frame_time = pipeline.frame_time();
    let followed = neighbour(at.checked_sub(1), "before").and_then(|before| {
        let after = neighbour(Some(at + 1), "after")?;
        let sides = [(at - 1, before), (at + 1, after)];
        let missing: Vec<(usize, &Prepared)> = sides
            .into_iter()
            .filter(|(j, _)| !bins.contains_key(j))
            .collect();
        // The new neighbour's triangles are binned while the fluid carries the vertices: the
        // binning's sort runs on one thread.
        let reconstructor = pipeline.prepared_reconstructor();
        let (carried, built) = reconstructor.install(|| {
            rayon::join(
                || {
                    let motions = [&*before.motion, &*after.motion];
                    carry(&own.mesh, &own.motion, motions, frame_time, spacing, cell)
                },
                || {
                    missing
                        .iter()
                        .map(|&(j, p)| (j, neighbour_bins(&p.mesh, spacing)))
                        .collect::<Vec<_>>()
                },
            )
        });
        bins.extend(built);
        let carried = carried.map_err(|e| e.to_string())?.ok_or_else(|| {
            own.ids_warning.clone().unwrap_or_else(|| {
                "the particles have no ids (and post.frame_time is not set to carry them by \
                 their velocities)"
                    .to_string()
            })
        })?;
        let surfaces = sides.map(|(j, p)| (&p.mesh, &bins[&j]));
        let mut mesh = own.mesh.clone();
        reconstructor
            .install(|| follow_carried(&mut mesh, &own.close, carried, surfaces, spacing, cell));
        Ok(mesh)
    });
    followed.unwrap_or_else(|why| {
        let message = format!("post-processed alone, not following the fluid: {why}");
        progress.warning(Some(&inputs[at]), &message);
        own.mesh.clone()
    })
}

/// The selection's files, and where their frame numbers jump by more than its usual step.
struct Selection<'a> {
    inputs: &'a [PathBuf],
    numbers: Vec<Option<u64>>,
    step: Option<u64>,
}

impl<'a> Selection<'a> {
    fn new(inputs: &'a [PathBuf]) -> Selection<'a> {
        let numbers: Vec<Option<u64>> = inputs.iter().map(|p| path_frame_number(p)).collect();
        let step = numbers
            .windows(2)
            .filter_map(|w| w[1]?.checked_sub(w[0]?))
            .filter(|&d| d > 0)
            .min();
        Selection {
            inputs,
            numbers,
            step,
        }
    }

    /// Whether frames `a` and `b` of the selection lie farther apart than the usual step.
    fn gap_between(&self, a: usize, b: usize) -> bool {
        match (self.numbers[a], self.numbers[b], self.step) {
            (Some(x), Some(y), Some(step)) => x.abs_diff(y) > step,
            _ => false,
        }
    }
}
