//! A set of frame numbers as a farm job names them: `1-10,20,30-40x5` (`--frames`).

use std::collections::BTreeSet;
use std::path::PathBuf;

use super::path_frame_number;
use crate::error::{Error, Result};

/// A set of frame numbers: `1-10,20,30-40x5` (ranges are inclusive; `xS` takes every S-th
/// number from the range's start).
#[derive(Debug, Clone, PartialEq, Eq)]
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
    /// Parses `1-10,20,30-40x5`; a bad item is an [`Error::Config`] naming it.
    pub fn parse(text: &str) -> Result<FrameSet> {
        let bad = |item: &str, why: &str| {
            Error::config(format!(
                "--frames {text}: {why} in '{item}' (expected a list like 1-10,20,30-40x5: \
                 numbers, inclusive ranges A-B, and ranges with a step A-BxS)"
            ))
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

    /// Whether frame `n` is in the set.
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
                Error::input(format!(
                    "--frames: '{}' has no frame number (the last digits of its name)",
                    path.display()
                ))
            })?;
            if self.contains(n) {
                kept.push(path);
            }
        }
        Ok(kept)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_sets_parse_lists_ranges_and_steps() {
        let set = FrameSet::parse("1-10, 20,30-40x5").unwrap();
        let kept: Vec<u64> = (0..50).filter(|&n| set.contains(n)).collect();
        assert_eq!(kept, [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 20, 30, 35, 40]);
        let set = FrameSet::parse("100-400x2").unwrap();
        assert!(set.contains(100) && set.contains(400) && !set.contains(101));
        for bad in ["", "1-", "5-1", "1-10x0", "a", "1,,2", "1-2-3"] {
            assert!(
                matches!(FrameSet::parse(bad), Err(Error::Config(_))),
                "{bad}"
            );
        }
        let present: BTreeSet<u64> = [1, 3].into();
        let (count, first) = FrameSet::parse("1-5")
            .unwrap()
            .missing(&present, 2)
            .unwrap();
        assert_eq!((count, first), (3, vec![2, 4]));
    }
}
