//! A whole sequence, `splash recon`'s and `splash iso`'s: every output named and checked
//! before any work, this job's share planned, the spacing taken from the sequence's first frame
//! whatever the shard, then each frame through the [`FramePipeline`].

use std::path::PathBuf;

use super::{FramePipeline, Plan, Progress, RunReport, run_plan};
use crate::config::Config;
use crate::error::Result;
use crate::frames::{Output, Shard, output_paths};
use crate::io::{InputFormat, MeshFormat};
use crate::iso::IsoRequest;

/// A run over many frames: one mesh per input file, each written whole or not at all.
#[derive(Debug, Clone)]
pub struct Batch {
    /// The selected frames, in frame order: the whole sequence, before sharding.
    pub inputs: Vec<PathBuf>,
    /// Every input's format; None: from each file's extension.
    pub input_format: Option<InputFormat>,
    /// Where the meshes go.
    pub output: Output,
    /// The mesh format.
    pub format: MeshFormat,
    /// Everything else: the reconstruction, and the up axis and attributes of the output.
    /// With `threads` set the reconstruction runs on its own pool, else in the caller's.
    pub config: Config,
    /// This job's part of the sequence; None: all of it.
    pub shard: Option<Shard>,
    /// Leaves frames whose output exists alone. Outputs are renamed into place whole, so an
    /// existing output is complete; an interrupted write leaves only a hidden temporary.
    pub skip_existing: bool,
    /// Stops at the first failing frame instead of going on with the others.
    pub fail_fast: bool,
    /// An isosurface of a particle quantity per frame (`splash iso`) instead of the surface.
    pub iso: Option<IsoRequest>,
}

impl Batch {
    /// Output paths of all frames, checked for collisions before any work starts.
    pub fn outputs(&self) -> Result<Vec<PathBuf>> {
        let ext = self.format.extension();
        output_paths(&self.inputs, &self.output, "mesh", "_surface", ext)
    }

    /// This job's share, with every output of the whole sequence checked (so that all shards
    /// agree) and the output directories checked writable.
    pub fn plan(&self) -> Result<Plan> {
        let outputs = self.outputs()?;
        let plan = Plan::new(&self.inputs, &outputs, self.shard, self.skip_existing);
        Ok(plan)
    }

    /// Reconstructs this job's frames in frame order. Errors before the first frame (bad
    /// settings, outputs that collide or cannot be written) end the run; a frame's error is in
    /// its outcome.
    pub fn run(&self, progress: &mut dyn Progress) -> Result<RunReport> {
        let plan = self.plan()?;
        let mut pipeline = FramePipeline::new(
            self.input_format,
            self.format,
            self.config.clone(),
            self.iso.clone(),
        )?;
        plan.check_writable()?;
        progress.started(&plan);
        if let Some(first) = plan.first {
            pipeline.spacing_from(&self.inputs[..first], progress);
        }
        Ok(run_plan(
            plan,
            self.fail_fast,
            progress,
            |input, output, progress| pipeline.frame(input, output, progress),
        ))
    }
}
