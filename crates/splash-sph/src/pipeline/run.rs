//! Running a plan: each frame in order, a failing frame reported without stopping the others
//! (unless `fail_fast`), the caller told of every frame as it ends, and a report at the end.

use std::path::{Path, PathBuf};

use super::Plan;
use crate::error::Result;
use crate::frames::path_frame_number;
use crate::report::{Clock, FrameStats, Observer};

/// What happened to one frame: its figures `S` (a reconstruction's [`FrameStats`], a
/// preview's) or its error.
#[derive(Debug)]
pub struct FrameOutcome<S = FrameStats> {
    /// The particle file.
    pub input: PathBuf,
    /// The file written (or that would have been).
    pub output: PathBuf,
    /// Frame number from the input's name.
    pub frame: Option<u64>,
    /// The figures, or why the frame has no output.
    pub result: Result<S>,
}

/// The end of a run.
#[derive(Debug)]
pub struct RunReport<S = FrameStats> {
    /// The job's share, as planned.
    pub plan: Plan,
    /// The frames attempted, in frame order.
    pub outcomes: Vec<FrameOutcome<S>>,
    /// Frames not attempted: a frame failed with `fail_fast` set, or the caller cancelled.
    pub not_attempted: usize,
}

impl<S> RunReport<S> {
    /// The frames that failed.
    pub fn failed(&self) -> impl Iterator<Item = &FrameOutcome<S>> {
        self.outcomes.iter().filter(|o| o.result.is_err())
    }

    /// Every frame of this job has its output: written now or found complete.
    pub fn complete(&self) -> bool {
        self.not_attempted == 0 && self.failed().next().is_none()
    }
}

/// What a run tells its caller as it goes (a console, a Python callback), and how it measures
/// a frame's reconstruction. Every method but `frame_done` has a default.
pub trait Progress<S = FrameStats> {
    /// The plan, before any frame.
    fn started(&mut self, _plan: &Plan) {}
    /// The spacing estimated once for the run, from frame `from`.
    fn spacing_estimated(&mut self, _from: &Path, _spacing: f32) {}
    /// Something that makes the output suspect, about frame `input` or the run (None).
    fn warning(&mut self, _input: Option<&Path>, _message: &str) {}
    /// Frame `done` of `total` has ended (or failed).
    fn frame_done(&mut self, outcome: &FrameOutcome<S>, done: usize, total: usize);
    /// Asked before each frame: true stops the run (the frames left count as not attempted).
    fn cancelled(&mut self) -> bool {
        false
    }
    /// The observer of the next reconstruction's stages (default: their wall times).
    fn observer(&mut self) -> Box<dyn Observer> {
        Box::new(Clock::default())
    }
    /// Adds what only the caller measures to a frame's figures once its surface is made (the
    /// CLI: the process's peak resident set size).
    fn measured(&mut self, _stats: &mut FrameStats) {}
}

/// Runs `work(input, output, progress)` on the plan's frames in order.
pub fn run_plan<S>(
    plan: Plan,
    fail_fast: bool,
    progress: &mut dyn Progress<S>,
    mut work: impl FnMut(&Path, &Path, &mut dyn Progress<S>) -> Result<S>,
) -> RunReport<S> {
    let total = plan.frames.len();
    let mut outcomes = Vec::with_capacity(total);
    let mut not_attempted = 0;
    for (k, (input, output)) in plan.frames.iter().enumerate() {
        if progress.cancelled() {
            not_attempted = total - k;
            break;
        }
        let result = work(input, output, progress);
        let outcome = FrameOutcome {
            input: input.clone(),
            output: output.clone(),
            frame: path_frame_number(input),
            result,
        };
        progress.frame_done(&outcome, k + 1, total);
        let failed = outcome.result.is_err();
        outcomes.push(outcome);
        if failed && fail_fast {
            not_attempted = total - k - 1;
            break;
        }
    }
    RunReport {
        plan,
        outcomes,
        not_attempted,
    }
}
