//! A sequence whose surfaces follow the fluid (`post.temporal`, issue 38): frame t is written
//! from its own post-processed surface moved towards its neighbours' (the frames beside it in
//! the selection) carried to its time ([`follow_fluid`]). A frame's neighbours are
//! reconstructed too, also where another job writes them (`--shard`) or their output exists
//! (`skip_existing`), so that every job writes the bytes one run over the whole sequence
//! writes. At most three prepared frames are held at once, with their triangles binned for
//! distance queries (each frame's once, for both frames beside it). A frame without both neighbours (the
//! ends of the selection, a gap in its frame numbers, a neighbour that fails or has no
//! particles, particles that cannot be matched) is post-processed alone, with a warning.

use std::collections::BTreeMap;
use std::collections::btree_map::Entry;
use std::path::PathBuf;

use super::frame::{Prepared, Ready};
use super::{FramePipeline, Plan, Progress, RunReport, run_plan};
use crate::error::{Error, Result};
use crate::frames::path_frame_number;
use crate::mesh::SurfaceBins;
use crate::temporal::{Neighbour, follow_fluid, neighbour_bins};

/// Runs the plan's frames of the selection `inputs`, each following the fluid from its
/// neighbours; see the module's header.
pub(super) fn run_following(
    inputs: &[PathBuf],
    plan: Plan,
    fail_fast: bool,
    progress: &mut dyn Progress,
    pipeline: &mut FramePipeline,
) -> RunReport {
    let selection = Selection::new(inputs);
    let (loader, writer) = (pipeline.loader(), pipeline.writer());
    // The frames' positions in the selection, in the order run_plan takes them.
    let mut positions = plan.positions.clone().into_iter();
    // Frames prepared, by position in the selection.
    let mut held: BTreeMap<usize, Result<Ready>> = BTreeMap::new();
    // Their triangles binned as neighbours, each once for both frames beside it.
    let mut bins: BTreeMap<usize, SurfaceBins> = BTreeMap::new();
    run_plan(plan, fail_fast, progress, |_, output, progress| {
        let at = positions.next().expect("one position per frame to do");
        held.retain(|&j, _| j + 1 >= at);
        bins.retain(|&j, _| j + 1 >= at);
        let near = at.saturating_sub(1)..(at + 2).min(inputs.len());
        for (j, path) in near.clone().zip(&inputs[near]) {
            if let Entry::Vacant(slot) = held.entry(j) {
                let prepared = loader
                    .load(path)
                    .and_then(|loaded| pipeline.prepare(path, loaded, progress));
                slot.insert(prepared);
            }
        }
        // The frame's own error stays its outcome; its neighbours keep only its message.
        let made = match held.remove(&at).expect("prepared above") {
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
        };
        made.and_then(|made| writer.write(output, made))
    })
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
        let mut mesh = own.mesh.clone();
        let sides = [(at - 1, before), (at + 1, after)];
        for (j, p) in sides {
            bins.entry(j)
                .or_insert_with(|| neighbour_bins(&p.mesh, spacing));
        }
        let neighbours = sides.map(|(j, p)| Neighbour {
            mesh: &p.mesh,
            bins: &bins[&j],
            motion: &p.motion,
        });
        pipeline
            .prepared_reconstructor()
            .install(|| {
                follow_fluid(
                    &mut mesh,
                    &own.motion,
                    neighbours,
                    frame_time,
                    spacing,
                    cell,
                )
            })
            .map_err(|e| e.to_string())?
            .ok_or_else(|| {
                own.ids_warning.clone().unwrap_or_else(|| {
                    "the particles have no ids (and post.frame_time is not set to carry them \
                     by their velocities)"
                        .to_string()
                })
            })?;
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
