//! The particle files a run covers, from what a user names: files, directories (the frame
//! sequence among their particle files, not recursively, hidden files skipped: see
//! [`frame_files`]) and glob patterns (`'sim/frame_*.ply'`, expanded here so that a shell's
//! argument limit never bites); then the frames a [`FrameSet`] keeps.

use std::collections::{BTreeMap, BTreeSet, HashSet};
use std::path::{Path, PathBuf};

use super::{FrameSet, input_extension, path_frame_number, sort_frames};
use crate::error::{Error, Result};
use crate::io::InputFormat;

fn is_glob(text: &str) -> bool {
    text.contains(['*', '?', '['])
}

/// The inputs of a run, and the files of scanned directories left out of it.
#[derive(Debug, Clone)]
pub struct Discovered {
    /// The particle files, in frame order, each once.
    pub files: Vec<PathBuf>,
    /// Files of the input directories that are not part of their frame sequence.
    pub skipped: Vec<PathBuf>,
}

fn listing_error(dir: &Path, e: std::io::Error) -> Error {
    Error::Io {
        path: dir.to_path_buf(),
        message: format!("cannot list the directory '{}': {e}", dir.display()),
        io_error: e,
    }
}

/// The particle files named by `inputs`, in frame order, each once.
///
/// A path that does not exist and is not a pattern is passed through, so that the frame is
/// reported as unreadable like any other bad frame. A directory without particle files or a
/// pattern matching nothing is an error.
pub fn discover(inputs: &[PathBuf]) -> Result<Discovered> {
    let mut files = Vec::new();
    let mut skipped = Vec::new();
    for input in inputs {
        let text = input.to_string_lossy();
        if input.is_dir() {
            let mut candidates = Vec::new();
            let entries = std::fs::read_dir(input).map_err(|e| listing_error(input, e))?;
            for entry in entries {
                let entry = entry.map_err(|e| listing_error(input, e))?;
                let path = entry.path();
                let hidden = entry.file_name().to_string_lossy().starts_with('.');
                if !hidden && path.is_file() && InputFormat::from_path(&path).is_ok() {
                    candidates.push(path);
                }
            }
            if candidates.is_empty() {
                bail_input!(
                    "the directory '{}' holds no particle files (.ply, .csv, .txt, .bin, .raw, .vtk, \
                     .vtu, .vtp, .bgeo, .bgeo.gz, .xyz)",
                    input.display()
                );
            }
            candidates.sort();
            let (mut frames, mut left) = frame_files(candidates);
            files.append(&mut frames);
            skipped.append(&mut left);
        } else if !input.exists() && is_glob(&text) {
            let options = glob::MatchOptions {
                require_literal_leading_dot: true,
                ..glob::MatchOptions::new()
            };
            let matches = glob::glob_with(&text, options)
                .map_err(|e| Error::config(format!("bad input pattern '{text}': {e}")))?;
            let before = files.len();
            for path in matches {
                let path = path.map_err(|e| {
                    let path = e.path().to_path_buf();
                    let message = format!("input pattern '{text}': {e}");
                    Error::Io {
                        path,
                        message,
                        io_error: e.into(),
                    }
                })?;
                if path.is_file() {
                    files.push(path);
                }
            }
            if files.len() == before {
                bail_input!("the input pattern '{text}' matches no file");
            }
        } else {
            files.push(input.clone());
        }
    }
    // The same file named twice (a directory and a pattern, say) is one frame.
    let mut seen = HashSet::new();
    files.retain(|f| seen.insert(f.canonicalize().unwrap_or_else(|_| f.clone())));
    sort_frames(&mut files);
    Ok(Discovered { files, skipped })
}

/// Splits a directory's particle files (sorted) into its frame sequence and the rest. A stray
/// `notes.txt` or `readme.txt` beside `frame_0001.ply`… is no frame: when some files carry a
/// frame number, those without one are left out, and of the rest the largest group sharing
/// one extension is the sequence (a tie goes to the extension that sorts first).
fn frame_files(candidates: Vec<PathBuf>) -> (Vec<PathBuf>, Vec<PathBuf>) {
    let extension = |p: &PathBuf| input_extension(p);
    let numbered = candidates.iter().any(|p| path_frame_number(p).is_some());
    let in_sequence = |p: &PathBuf| !numbered || path_frame_number(p).is_some();
    let mut counts: BTreeMap<Option<String>, usize> = BTreeMap::new();
    for path in candidates.iter().filter(|p| in_sequence(p)) {
        *counts.entry(extension(path)).or_default() += 1;
    }
    let most = counts.values().copied().max().unwrap_or(0);
    let chosen = counts.into_iter().find(|&(_, n)| n == most).map(|(e, _)| e);
    candidates
        .into_iter()
        .partition(|p| in_sequence(p) && Some(extension(p)) == chosen)
}

/// The frames of a run, with what the user should hear about the selection.
#[derive(Debug, Clone)]
pub struct Selection {
    /// The selected frames, in frame order.
    pub files: Vec<PathBuf>,
    /// Things that make the selection suspect: directory files outside the sequence, numbers
    /// of the frame set with no input.
    pub warnings: Vec<String>,
}

/// The frames of `inputs` (files, directories, patterns) that `frames` selects, in frame
/// order. Selecting nothing is an error.
pub fn select(inputs: &[PathBuf], frames: Option<&str>) -> Result<Selection> {
    let set = frames.map(|text| Ok::<_, Error>((text, FrameSet::parse(text)?)));
    let set = set.transpose()?;
    let discovered = discover(inputs)?;
    let mut warnings = Vec::new();
    if !discovered.skipped.is_empty() {
        let shown: Vec<String> = discovered
            .skipped
            .iter()
            .take(5)
            .map(|p| format!("'{}'", p.display()))
            .collect();
        let more = discovered.skipped.len() - shown.len();
        warnings.push(format!(
            "{} files of the input directories are not part of the frame sequence and are \
             skipped: {}{}",
            discovered.skipped.len(),
            shown.join(", "),
            if more > 0 {
                format!(" and {more} more")
            } else {
                String::new()
            }
        ));
    }
    let Some((text, set)) = set else {
        return Ok(Selection {
            files: discovered.files,
            warnings,
        });
    };
    let files = set.select(discovered.files)?;
    let present: BTreeSet<u64> = files.iter().filter_map(|p| path_frame_number(p)).collect();
    if let Some((count, first)) = set.missing(&present, 5)
        && count > 0
    {
        let first: Vec<String> = first.iter().map(u64::to_string).collect();
        warnings.push(format!(
            "{count} frames of --frames have no input (first: {})",
            first.join(", ")
        ));
    }
    if files.is_empty() {
        bail_input!("--frames {text}: no input has one of these frame numbers");
    }
    Ok(Selection { files, warnings })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_directory_sequence_is_its_commonest_numbered_extension() {
        let files = [
            "f_1.bgeo.gz",
            "f_2.bgeo.gz",
            "f_3.bgeo.gz",
            "f_1.bgeo",
            "notes.txt",
        ];
        let (frames, left) = frame_files(files.iter().map(PathBuf::from).collect());
        assert_eq!(
            frames,
            ["f_1.bgeo.gz", "f_2.bgeo.gz", "f_3.bgeo.gz"].map(PathBuf::from)
        );
        assert_eq!(left, ["f_1.bgeo", "notes.txt"].map(PathBuf::from));
    }
}
