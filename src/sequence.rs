//! Frame sequences: which particle files a run covers and in what order.
//!
//! - Inputs are files, directories (the frame sequence among their particle files, not
//!   recursively, hidden files skipped: see [`frame_files`]) or quoted glob patterns (`'sim/frame_*.ply'`, expanded here so that the shell's
//!   argument limit never bites).
//! - A frame's number is the last run of digits in its file stem; frames are ordered by it,
//!   numerically (`f_9` before `f_10`), frames without a number after the numbered ones.
//! - `--frames` keeps the frames whose number is in a list of ranges ([`FrameSet`]).
//! - `--shard K/N` keeps every N-th frame of the selection ([`Shard`]), so that N independent
//!   jobs cover each frame exactly once.

use std::collections::{BTreeMap, BTreeSet, HashSet};
use std::fmt;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};
use clap::Args;

use splash_sph::InputFormat;

/// The last run of digits in a file stem: `frame_0042` → 42.
pub fn frame_number(stem: &str) -> Option<u64> {
    let (start, end) = last_digits(stem)?;
    stem[start..end].parse().ok()
}

/// Byte range of the last run of ASCII digits in `s`.
fn last_digits(s: &str) -> Option<(usize, usize)> {
    let end = s.rfind(|c: char| c.is_ascii_digit())? + 1;
    let start = s[..end]
        .rfind(|c: char| !c.is_ascii_digit())
        .map_or(0, |i| i + 1);
    Some((start, end))
}

/// The frame number of a path, from its file stem.
pub fn path_frame_number(path: &Path) -> Option<u64> {
    frame_number(&input_stem(path)?)
}

/// Double extensions of particle files: `fluid_0042.bgeo.gz` is frame 42 of stem `fluid_0042`.
const DOUBLE_EXTENSIONS: [&str; 2] = [".bgeo.gz", ".bgeo.sc"];

/// The file name without its particle extension, the double ones ([`DOUBLE_EXTENSIONS`])
/// included: `f_7.ply` → `f_7`, `fluid.0042.bgeo.gz` → `fluid.0042`.
pub fn input_stem(path: &Path) -> Option<String> {
    let name = path.file_name()?.to_string_lossy();
    let lower = name.to_ascii_lowercase();
    for double in DOUBLE_EXTENSIONS {
        if lower.len() > double.len() && lower.ends_with(double) {
            return Some(name[..name.len() - double.len()].to_owned());
        }
    }
    Some(path.file_stem()?.to_string_lossy().into_owned())
}

/// The particle extension, lower case, double ones included: `bgeo.gz`, `ply`.
fn input_extension(path: &Path) -> Option<String> {
    let name = path.file_name()?.to_string_lossy().to_ascii_lowercase();
    for double in DOUBLE_EXTENSIONS {
        if name.len() > double.len() && name.ends_with(double) {
            return Some(double[1..].to_owned());
        }
    }
    Some(path.extension()?.to_string_lossy().to_ascii_lowercase())
}

/// `stem` with its frame number zero-padded to at least `width` digits: `f_9` → `f_0009`.
/// Longer numbers and stems without digits are returned unchanged.
pub fn padded_stem(stem: &str, width: usize) -> String {
    match last_digits(stem) {
        Some((start, end)) if end - start < width => {
            let digits = &stem[start..end];
            format!("{}{digits:0>width$}{}", &stem[..start], &stem[end..])
        }
        _ => stem.to_owned(),
    }
}

fn is_glob(text: &str) -> bool {
    text.contains(['*', '?', '['])
}

/// The particle files named by the command line's inputs, in frame order, each once.
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
            let entries = std::fs::read_dir(input)
                .with_context(|| format!("cannot list the directory '{}'", input.display()))?;
            for entry in entries {
                let entry = entry
                    .with_context(|| format!("cannot list the directory '{}'", input.display()))?;
                let path = entry.path();
                let hidden = entry.file_name().to_string_lossy().starts_with('.');
                if !hidden && path.is_file() && InputFormat::from_path(&path).is_ok() {
                    candidates.push(path);
                }
            }
            if candidates.is_empty() {
                bail!(
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
                .map_err(|e| anyhow!("bad input pattern '{text}': {e}"))?;
            let before = files.len();
            for path in matches {
                let path = path.map_err(|e| anyhow!("input pattern '{text}': {e}"))?;
                if path.is_file() {
                    files.push(path);
                }
            }
            if files.len() == before {
                bail!("the input pattern '{text}' matches no file");
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

/// The inputs of a run, and the files of scanned directories left out of it.
pub struct Discovered {
    pub files: Vec<PathBuf>,
    pub skipped: Vec<PathBuf>,
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

/// Orders paths by frame number, numerically; paths without one go last; ties keep their order.
pub fn sort_frames(paths: &mut [PathBuf]) {
    paths.sort_by_key(|p| {
        let n = path_frame_number(p);
        (n.is_none(), n)
    });
}

/// A set of frame numbers: `1-10,20,30-40x5` (ranges are inclusive; `xS` takes every S-th
/// number from the range's start).
#[derive(Debug, Clone, PartialEq, Eq)]
/// The options that pick a job's frames, shared by `recon` and `preview`.
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

/// The frames of `inputs` (files, directories, patterns) that `--frames` selects, in frame
/// order; warns of directory files outside the sequence and of selected numbers with no input.
pub fn select(
    inputs: &[PathBuf],
    frames: Option<&str>,
    console: &crate::log::Console,
) -> Result<Vec<PathBuf>> {
    let frames = frames.map(|text| Ok::<_, anyhow::Error>((text, FrameSet::parse(text)?)));
    let frames = frames.transpose()?;
    let discovered = discover(inputs)?;
    let mut inputs = discovered.files;
    if !discovered.skipped.is_empty() {
        let shown: Vec<String> = discovered
            .skipped
            .iter()
            .take(5)
            .map(|p| format!("'{}'", p.display()))
            .collect();
        let more = discovered.skipped.len() - shown.len();
        console.warn(
            None,
            &format!(
                "{} files of the input directories are not part of the frame sequence and \
                 are skipped: {}{}",
                discovered.skipped.len(),
                shown.join(", "),
                if more > 0 {
                    format!(" and {more} more")
                } else {
                    String::new()
                }
            ),
        );
    }
    let Some((text, frames)) = frames else {
        return Ok(inputs);
    };
    inputs = frames.select(inputs)?;
    let present: BTreeSet<u64> = inputs.iter().filter_map(|p| path_frame_number(p)).collect();
    if let Some((count, first)) = frames.missing(&present, 5)
        && count > 0
    {
        let first: Vec<String> = first.iter().map(u64::to_string).collect();
        console.warn(
            None,
            &format!(
                "{count} frames of --frames have no input (first: {})",
                first.join(", ")
            ),
        );
    }
    if inputs.is_empty() {
        bail!("--frames {text}: no input has one of these frame numbers");
    }
    Ok(inputs)
}

impl FarmArgs {
    /// The `--shard` asked for, `auto/N` read from the environment.
    pub fn shard(&self) -> Result<Option<Shard>> {
        self.shard
            .as_deref()
            .map(|s| Shard::parse(s, |name| std::env::var(name).ok()))
            .transpose()
    }
}

pub struct FrameSet {
    ranges: Vec<FrameRange>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct FrameRange {
    first: u64,
    last: u64,
    step: u64,
}

impl FrameRange {
    fn contains(&self, n: u64) -> bool {
        (self.first..=self.last).contains(&n) && (n - self.first).is_multiple_of(self.step)
    }
}

impl FrameSet {
    pub fn parse(text: &str) -> Result<FrameSet> {
        let bad = |item: &str, why: &str| {
            anyhow!(
                "--frames {text}: {why} in '{item}' (expected a list like 1-10,20,30-40x5: \
                 numbers, inclusive ranges A-B, and ranges with a step A-BxS)"
            )
        };
        let number = |item: &str, s: &str| {
            s.trim()
                .parse::<u64>()
                .map_err(|_| bad(item, &format!("'{}' is not a frame number", s.trim())))
        };
        let mut ranges = Vec::new();
        for item in text.split(',') {
            let item = item.trim();
            if item.is_empty() {
                return Err(bad(item, "an empty item"));
            }
            let (span, step) = match item.split_once(['x', 'X']) {
                Some((span, step)) => (span, number(item, step)?),
                None => (item, 1),
            };
            if step == 0 {
                return Err(bad(item, "a step of 0"));
            }
            let (first, last) = match span.split_once('-') {
                Some((a, b)) => (number(item, a)?, number(item, b)?),
                None => {
                    let n = number(item, span)?;
                    (n, n)
                }
            };
            if first > last {
                return Err(bad(item, "a range that ends before it starts"));
            }
            ranges.push(FrameRange { first, last, step });
        }
        Ok(FrameSet { ranges })
    }

    pub fn contains(&self, n: u64) -> bool {
        self.ranges.iter().any(|r| r.contains(n))
    }

    /// Numbers in the set that are not in `present`: their count and the first `show` of them.
    /// Gives up (None) on sets of more than ten million numbers.
    pub fn missing(&self, present: &BTreeSet<u64>, show: usize) -> Option<(u64, Vec<u64>)> {
        let total: u64 = self
            .ranges
            .iter()
            .map(|r| (r.last - r.first) / r.step + 1)
            .sum();
        if total > 10_000_000 {
            return None;
        }
        let mut wanted = BTreeSet::new();
        for r in &self.ranges {
            wanted.extend((r.first..=r.last).step_by(r.step as usize));
        }
        let missing: Vec<u64> = wanted.difference(present).copied().collect();
        Some((
            missing.len() as u64,
            missing.into_iter().take(show).collect(),
        ))
    }

    /// Keeps the paths whose frame number is in the set; a path without one is an error.
    pub fn select(&self, paths: Vec<PathBuf>) -> Result<Vec<PathBuf>> {
        let mut kept = Vec::new();
        for path in paths {
            let n = path_frame_number(&path).ok_or_else(|| {
                anyhow!(
                    "--frames: '{}' has no frame number (the last digits of its name)",
                    path.display()
                )
            })?;
            if self.contains(n) {
                kept.push(path);
            }
        }
        Ok(kept)
    }
}

/// One of N jobs that share a sequence: job K (1-based) takes the frames at positions
/// K-1, K-1+N, K-1+2N, … of the selected frames, so that the jobs' costs stay even while a
/// simulation grows more detailed, and together they take every frame exactly once.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// 0-based.
    index: usize,
    count: usize,
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index + 1, self.count)
    }
}

impl Shard {
    pub fn new(k: usize, n: usize) -> Result<Shard> {
        if n == 0 || k == 0 || k > n {
            bail!("--shard {k}/{n}: K must be between 1 and N (shards are numbered 1 to N)");
        }
        Ok(Shard {
            index: k - 1,
            count: n,
        })
    }

    /// `K/N` (1 ≤ K ≤ N), or `auto/N`: K = `SLURM_ARRAY_TASK_ID` mod N + 1, from the task's
    /// own ID only (`var` reads the environment). The N tasks of `--array=0-(N-1)` or
    /// `1-N` (any N consecutive IDs) get the N shards, and a task resubmitted alone
    /// (`sbatch --array=5`, where SLURM sets the array's bounds to 5) keeps its shard. Arrays
    /// with a step, or spanning more than N IDs, would give two tasks one shard: refused.
    pub fn parse(text: &str, var: impl Fn(&str) -> Option<String>) -> Result<Shard> {
        let usage = || anyhow!("--shard {text}: expected K/N (1 ≤ K ≤ N) or auto/N");
        let (k, n) = text.split_once('/').ok_or_else(usage)?;
        let n: usize = n.trim().parse().map_err(|_| usage())?;
        if k.trim() != "auto" {
            let k: usize = k.trim().parse().map_err(|_| usage())?;
            return Shard::new(k, n);
        }
        if n == 0 {
            bail!("--shard auto/0: N must be at least 1");
        }
        let read = |name: &str| -> Result<Option<u64>> {
            var(name)
                .map(|v| {
                    v.trim()
                        .parse()
                        .map_err(|_| anyhow!("--shard auto/{n}: {name}={v} is not a task ID"))
                })
                .transpose()
        };
        let id = read("SLURM_ARRAY_TASK_ID")?.ok_or_else(|| {
            anyhow!(
                "--shard auto/{n}: SLURM_ARRAY_TASK_ID is not set (it is set in SLURM array \
                 jobs, sbatch --array; with another scheduler pass --shard K/{n} with K from its \
                 task index, 1 to {n})"
            )
        })?;
        if let Some(step) = read("SLURM_ARRAY_TASK_STEP")?.filter(|&s| s > 1) {
            bail!(
                "--shard auto/{n}: the array has a step of {step} (SLURM_ARRAY_TASK_STEP), so \
                 task ID mod {n} would give two tasks the same frames; submit --array=0-{} \
                 without a step, or pass K yourself: --shard $((SLURM_ARRAY_TASK_ID / {step} + \
                 1))/{n} for --array=0-{}:{step}",
                n - 1,
                (n as u64 - 1) * step
            );
        }
        if let (Some(min), Some(max)) =
            (read("SLURM_ARRAY_TASK_MIN")?, read("SLURM_ARRAY_TASK_MAX")?)
            && max.saturating_sub(min) >= n as u64
        {
            bail!(
                "--shard auto/{n}: the array's task IDs run from {min} to {max}, more than {n}, \
                 so tasks {min} and {} would do the same frames; submit {n} tasks, \
                 --array=0-{} or --array=1-{n}",
                min + n as u64,
                n - 1
            );
        }
        Shard::new((id % n as u64) as usize + 1, n)
    }

    /// Whether position `i` of the selected frames belongs to this shard.
    pub fn takes(&self, i: usize) -> bool {
        i % self.count == self.index
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn double_extensions_are_one_extension() {
        assert_eq!(
            input_stem(Path::new("h/fluid.0042.bgeo.gz")).unwrap(),
            "fluid.0042"
        );
        assert_eq!(input_stem(Path::new("f_7.BGEO.SC")).unwrap(), "f_7");
        assert_eq!(input_stem(Path::new("f_7.ply")).unwrap(), "f_7");
        assert_eq!(input_stem(Path::new("f_7.gz")).unwrap(), "f_7");
        assert_eq!(path_frame_number(Path::new("fluid_12.bgeo.gz")), Some(12));
        assert_eq!(
            input_extension(Path::new("a/F_1.Bgeo.Gz")).unwrap(),
            "bgeo.gz"
        );
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

    #[test]
    fn frame_numbers_come_from_the_last_digits() {
        assert_eq!(frame_number("frame_0042"), Some(42));
        assert_eq!(frame_number("run2_f_9"), Some(9));
        assert_eq!(frame_number("f10b"), Some(10));
        assert_eq!(frame_number("fluid"), None);
    }

    #[test]
    fn stems_are_padded() {
        assert_eq!(padded_stem("f_9", 4), "f_0009");
        assert_eq!(padded_stem("run2_f10b", 4), "run2_f0010b");
        assert_eq!(padded_stem("frame_12345", 4), "frame_12345");
        assert_eq!(padded_stem("fluid", 4), "fluid");
    }

    #[test]
    fn frames_sort_numerically() {
        let mut paths: Vec<PathBuf> = ["f_10.ply", "zzz.ply", "f_9.ply", "f_0011.ply", "a.ply"]
            .iter()
            .map(PathBuf::from)
            .collect();
        sort_frames(&mut paths);
        let names: Vec<_> = paths.iter().map(|p| p.to_str().unwrap()).collect();
        assert_eq!(
            names,
            ["f_9.ply", "f_10.ply", "f_0011.ply", "zzz.ply", "a.ply"]
        );
    }

    #[test]
    fn frame_sets_parse_lists_ranges_and_steps() {
        let set = FrameSet::parse("1-10, 20,30-40x5").unwrap();
        let kept: Vec<u64> = (0..50).filter(|&n| set.contains(n)).collect();
        assert_eq!(kept, [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 20, 30, 35, 40]);
        let set = FrameSet::parse("100-400x2").unwrap();
        assert!(set.contains(100) && set.contains(400) && !set.contains(101));
        for bad in ["", "1-", "5-1", "1-10x0", "a", "1,,2", "1-2-3"] {
            assert!(FrameSet::parse(bad).is_err(), "{bad}");
        }
        let present: BTreeSet<u64> = [1, 3].into();
        let (count, first) = FrameSet::parse("1-5")
            .unwrap()
            .missing(&present, 2)
            .unwrap();
        assert_eq!((count, first), (3, vec![2, 4]));
    }

    #[test]
    fn shards_cover_every_frame_exactly_once() {
        for frames in [0, 1, 7, 21, 100] {
            for n in [1, 2, 3, 4, 16, 150] {
                let mut seen = vec![0; frames];
                for k in 1..=n {
                    let shard = Shard::new(k, n).unwrap();
                    for (i, s) in seen.iter_mut().enumerate() {
                        if shard.takes(i) {
                            *s += 1;
                        }
                    }
                }
                assert!(seen.iter().all(|&s| s == 1), "{frames} frames, {n} shards");
            }
        }
        assert!(Shard::new(0, 4).is_err());
        assert!(Shard::new(5, 4).is_err());
        assert!(Shard::parse("1/0", |_| None).is_err());
        assert!(Shard::parse("x/4", |_| None).is_err());
        assert_eq!(
            Shard::parse(" 2/4", |_| None).unwrap(),
            Shard::new(2, 4).unwrap()
        );
    }

    /// A SLURM task's environment: its ID, and the array's bounds and step where given.
    fn slurm(
        id: u64,
        bounds: Option<(u64, u64)>,
        step: Option<u64>,
    ) -> impl Fn(&str) -> Option<String> {
        move |name: &str| match name {
            "SLURM_ARRAY_TASK_ID" => Some(id.to_string()),
            "SLURM_ARRAY_TASK_MIN" => bounds.map(|b| b.0.to_string()),
            "SLURM_ARRAY_TASK_MAX" => bounds.map(|b| b.1.to_string()),
            "SLURM_ARRAY_TASK_STEP" => step.map(|s| s.to_string()),
            _ => None,
        }
    }

    #[test]
    fn auto_shards_are_a_permutation_for_0_and_1_based_arrays() {
        for n in [1, 2, 5, 16] {
            for first in [0, 1, 7] {
                let last = first + n - 1;
                let mut shards: Vec<usize> = (first..=last)
                    .map(|id| {
                        Shard::parse(
                            &format!("auto/{n}"),
                            slurm(id, Some((first, last)), Some(1)),
                        )
                        .unwrap()
                        .index
                    })
                    .collect();
                shards.sort();
                assert_eq!(
                    shards,
                    (0..n as usize).collect::<Vec<_>>(),
                    "{first}-{last}"
                );
            }
        }
        // The README's rule: K = ID mod N + 1.
        let shard = |id, bounds| Shard::parse("auto/16", slurm(id, bounds, None)).unwrap();
        assert_eq!(shard(0, Some((0, 15))), Shard::new(1, 16).unwrap());
        assert_eq!(shard(3, Some((0, 15))), Shard::new(4, 16).unwrap());
        assert_eq!(shard(3, Some((1, 16))), Shard::new(4, 16).unwrap());
        assert_eq!(shard(16, Some((1, 16))), Shard::new(1, 16).unwrap());
    }

    #[test]
    fn a_resubmitted_task_keeps_its_shard() {
        // `sbatch --array=5` sets the array's bounds to 5 and 5; a list of killed tasks
        // (`--array=5,9`) to 5 and 9.
        for (first, last) in [(0, 15), (1, 16)] {
            for id in first..=last {
                let original = Shard::parse("auto/16", slurm(id, Some((first, last)), Some(1)));
                let alone = Shard::parse("auto/16", slurm(id, Some((id, id)), Some(1)));
                assert_eq!(
                    original.unwrap(),
                    alone.unwrap(),
                    "task {id} of {first}-{last}"
                );
            }
        }
        let listed = Shard::parse("auto/16", slurm(9, Some((5, 9)), None)).unwrap();
        assert_eq!(listed, Shard::new(10, 16).unwrap());
    }

    #[test]
    fn auto_shards_refuse_what_would_repeat_frames() {
        fn error(env: impl Fn(&str) -> Option<String>) -> String {
            Shard::parse("auto/16", env).unwrap_err().to_string()
        }
        let stepped = error(slurm(4, Some((0, 30)), Some(2)));
        assert!(
            stepped.contains("a step of 2")
                && stepped.contains("--shard $((SLURM_ARRAY_TASK_ID / 2 + 1))/16"),
            "{stepped}"
        );
        let wide = error(slurm(3, Some((0, 16)), None));
        assert!(
            wide.contains("tasks 0 and 16 would do the same frames"),
            "{wide}"
        );
        assert!(error(slurm(3, Some((0, 31)), Some(1))).contains("from 0 to 31"));
        let text = |id: &'static str| {
            move |name: &str| (name == "SLURM_ARRAY_TASK_ID").then(|| id.to_owned())
        };
        assert!(error(text("x")).contains("SLURM_ARRAY_TASK_ID=x is not a task ID"));
        assert!(error(text("-1")).contains("is not a task ID"));
        let unset = Shard::parse("auto/4", |_| None).unwrap_err().to_string();
        assert!(unset.contains("SLURM_ARRAY_TASK_ID is not set"), "{unset}");
        assert!(Shard::parse("auto/0", slurm(0, None, None)).is_err());
    }
}
