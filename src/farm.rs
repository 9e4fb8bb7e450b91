//! The options that pick a job's frames (`--frames`, `--shard`, `--skip-existing`,
//! `--fail-fast`), shared by `recon`, `iso` and `preview`; the rules are the library's
//! (`splash_sph::frames`, `splash_sph::pipeline`).

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use splash_sph::frames::{self, Shard};

use crate::log::Console;

/// The options that pick a job's frames.
#[derive(Args)]
pub struct FarmArgs {
    /// Only these frame numbers: A-B ranges, A-BxS every S-th, lists (1-10,20,30-40x5).
    #[arg(long, value_name = "LIST")]
    pub frames: Option<String>,

    /// Job K of N (1 ≤ K ≤ N) takes every N-th selected frame, from the K-th; auto/N takes
    /// K = SLURM_ARRAY_TASK_ID mod N + 1 (arrays 0-(N-1) or 1-N; a task resubmitted alone
    /// keeps its frames).
    #[arg(long, value_name = "K/N")]
    pub shard: Option<String>,

    /// Leave frames whose output exists alone (outputs are renamed into place whole, so an
    /// existing one is complete): a killed run restarted with this flag finishes the rest.
    #[arg(long)]
    pub skip_existing: bool,

    /// Stop at the first failing frame (default: report it and go on).
    #[arg(long)]
    pub fail_fast: bool,
}

impl FarmArgs {
    /// The `--shard` asked for, `auto/N` read from the environment.
    pub fn shard(&self) -> Result<Option<Shard>> {
        Ok(self.shard.as_deref().map(Shard::from_env).transpose()?)
    }

    /// The frames of `inputs` (files, directories, patterns) that `--frames` selects, in
    /// frame order; warns of directory files outside the sequence and of selected numbers with
    /// no input.
    pub fn select(&self, inputs: &[PathBuf], console: &Console) -> Result<Vec<PathBuf>> {
        let selection = frames::select(inputs, self.frames.as_deref())?;
        for warning in &selection.warnings {
            console.warn(None, warning);
        }
        Ok(selection.files)
    }
}
