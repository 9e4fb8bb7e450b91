//! A job's share of a sequence, known before any frame is read: the frames of its shard, those
//! whose output exists and are left alone (`skip_existing`), and the rest, to do; and the
//! check that the output directories take files, so that a run fails at once rather than after
//! each frame's work.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::frames::Shard;

/// This job's share of the sequence.
#[derive(Debug, Clone)]
pub struct Plan {
    /// Frames selected (by the inputs and the frame set), before sharding.
    pub selected: usize,
    /// The job's shard; None: all of the selection.
    pub shard: Option<Shard>,
    /// Frames of this shard.
    pub assigned: usize,
    /// Frames of this shard whose output exists, left alone.
    pub skipped: Vec<PathBuf>,
    /// The frames to do: (input, output), in frame order.
    pub frames: Vec<(PathBuf, PathBuf)>,
    /// Each frame to do's position in the selection (its neighbours are the frames beside it).
    pub positions: Vec<usize>,
    /// Position in the selection of the first frame to do (the frames before it are where a
    /// run over the whole sequence would have estimated the spacing).
    pub first: Option<usize>,
}

impl Plan {
    /// The share of `shard` of `inputs` (the whole selection, in frame order) and their
    /// `outputs`; with `skip_existing`, frames whose output is a file are skipped: outputs are
    /// renamed into place whole, so an existing one is complete.
    pub fn new(
        inputs: &[PathBuf],
        outputs: &[PathBuf],
        shard: Option<Shard>,
        skip_existing: bool,
    ) -> Plan {
        let assigned: Vec<usize> = (0..inputs.len())
            .filter(|&i| shard.is_none_or(|s| s.takes(i)))
            .collect();
        let (skipped, to_do): (Vec<usize>, Vec<usize>) = assigned
            .iter()
            .partition(|&&i| skip_existing && outputs[i].is_file());
        Plan {
            selected: inputs.len(),
            shard,
            assigned: assigned.len(),
            skipped: skipped.iter().map(|&i| inputs[i].clone()).collect(),
            frames: to_do
                .iter()
                .map(|&i| (inputs[i].clone(), outputs[i].clone()))
                .collect(),
            first: to_do.first().copied(),
            positions: to_do,
        }
    }

    /// Frames to do.
    pub fn to_do(&self) -> usize {
        self.frames.len()
    }

    /// Creates the directories the frames to do are written into, and checks that each takes a
    /// file.
    pub fn check_writable(&self) -> Result<()> {
        let mut dirs: Vec<&Path> = self.frames.iter().map(|(_, o)| output_dir(o)).collect();
        dirs.sort();
        dirs.dedup();
        dirs.into_iter().try_for_each(check_writable)
    }
}

/// The directory a file is written into.
fn output_dir(output: &Path) -> &Path {
    match output.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    }
}

fn unusable(dir: &Path, doing: &str, e: std::io::Error) -> Error {
    Error::Io {
        path: dir.to_path_buf(),
        message: format!(
            "cannot {doing} the output directory '{}': {e}; no frame was reconstructed",
            dir.display()
        ),
        io_error: e,
    }
}

/// Creates `dir` if needed and writes (and removes) a small file in it.
fn check_writable(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| unusable(dir, "create", e))?;
    let probe = dir.join(format!(".splash-write-check-{}", std::process::id()));
    let written = std::fs::OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(true)
        .open(&probe);
    let _ = std::fs::remove_file(&probe);
    written.map_err(|e| unusable(dir, "write in", e))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_and_existing_outputs_split_the_sequence() {
        let dir = std::env::temp_dir().join(format!("splash-plan-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let inputs: Vec<PathBuf> = (1..=5).map(|i| dir.join(format!("f_{i}.ply"))).collect();
        let outputs: Vec<PathBuf> = (1..=5).map(|i| dir.join(format!("m_{i}.obj"))).collect();
        std::fs::write(&outputs[2], "done").unwrap();
        let plan = Plan::new(&inputs, &outputs, Some(Shard::new(1, 2).unwrap()), true);
        assert_eq!((plan.selected, plan.assigned, plan.to_do()), (5, 3, 2));
        assert_eq!(plan.skipped, [inputs[2].clone()]);
        assert_eq!(plan.frames[1], (inputs[4].clone(), outputs[4].clone()));
        assert_eq!(plan.first, Some(0));
        let second = Plan::new(&inputs, &outputs, Some(Shard::new(2, 2).unwrap()), false);
        assert_eq!((second.assigned, second.first), (2, Some(1)));
        assert!(second.check_writable().is_ok());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
