//! Frame sequences as simulators write them and farms split them: a frame's number is the last
//! run of digits in its file stem (`frame_0042.ply` → 42), frames run in number order.
//!
//! - [`select`]: which particle files a run covers, from files, directories and globs, and
//!   the frame numbers it keeps (`1-10,20,30-40x5`);
//! - [`Shard`]: job K of N takes every N-th selected frame;
//! - [`Output`]: where each frame's result goes (a directory, a pattern, beside the input).

mod discovery;
mod naming;
mod set;
mod shard;

use std::path::{Path, PathBuf};

pub use discovery::{Selection, select};
pub use naming::{Output, output_paths};
pub(crate) use set::FrameSet;
pub use shard::Shard;

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

/// The frame number of a path, from its file stem (its file name without the particle
/// extension, `.bgeo.gz` and `.bgeo.sc` included).
pub fn path_frame_number(path: &Path) -> Option<u64> {
    frame_number(&input_stem(path)?)
}

/// Double extensions of particle files: `fluid_0042.bgeo.gz` is frame 42 of stem `fluid_0042`.
const DOUBLE_EXTENSIONS: [&str; 2] = [".bgeo.gz", ".bgeo.sc"];

/// The file name without its particle extension, the double ones (`.bgeo.gz`, `.bgeo.sc`)
/// included: `f_7.ply` → `f_7`, `fluid.0042.bgeo.gz` → `fluid.0042`.
pub(crate) fn input_stem(path: &Path) -> Option<String> {
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
pub(crate) fn padded_stem(stem: &str, width: usize) -> String {
    match last_digits(stem) {
        Some((start, end)) if end - start < width => {
            let digits = &stem[start..end];
            format!("{}{digits:0>width$}{}", &stem[..start], &stem[end..])
        }
        _ => stem.to_owned(),
    }
}

/// Orders paths by frame number, numerically; paths without one go last; ties keep their order.
pub(crate) fn sort_frames(paths: &mut [PathBuf]) {
    paths.sort_by_key(|p| {
        let n = path_frame_number(p);
        (n.is_none(), n)
    });
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
}
