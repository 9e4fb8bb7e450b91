//! Farm jobs that share a sequence: job K of N takes every N-th selected frame (`--shard K/N`),
//! K from SLURM's array task ID with `auto/N`.

use std::fmt;

use crate::error::{Error, Result};

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
    /// Job `k` (1-based) of `n`.
    pub fn new(k: usize, n: usize) -> Result<Shard> {
        if n == 0 || k == 0 || k > n {
            bail_config!("--shard {k}/{n}: K must be between 1 and N (shards are numbered 1 to N)");
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
        let usage = || {
            Error::config(format!(
                "--shard {text}: expected K/N (1 ≤ K ≤ N) or auto/N"
            ))
        };
        let (k, n) = text.split_once('/').ok_or_else(usage)?;
        let n: usize = n.trim().parse().map_err(|_| usage())?;
        if k.trim() != "auto" {
            let k: usize = k.trim().parse().map_err(|_| usage())?;
            return Shard::new(k, n);
        }
        if n == 0 {
            bail_config!("--shard auto/0: N must be at least 1");
        }
        let read = |name: &str| -> Result<Option<u64>> {
            var(name)
                .map(|v| {
                    v.trim().parse().map_err(|_| {
                        Error::config(format!("--shard auto/{n}: {name}={v} is not a task ID"))
                    })
                })
                .transpose()
        };
        let id = read("SLURM_ARRAY_TASK_ID")?.ok_or_else(|| {
            Error::config(format!(
                "--shard auto/{n}: SLURM_ARRAY_TASK_ID is not set (it is set in SLURM array \
                 jobs, sbatch --array; with another scheduler pass --shard K/{n} with K from its \
                 task index, 1 to {n})"
            ))
        })?;
        if let Some(step) = read("SLURM_ARRAY_TASK_STEP")?.filter(|&s| s > 1) {
            bail_config!(
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
            bail_config!(
                "--shard auto/{n}: the array's task IDs run from {min} to {max}, more than {n}, \
                 so tasks {min} and {} would do the same frames; submit {n} tasks, \
                 --array=0-{} or --array=1-{n}",
                min + n as u64,
                n - 1
            );
        }
        Shard::new((id % n as u64) as usize + 1, n)
    }

    /// Parses `K/N` or `auto/N` with the process's environment.
    pub fn from_env(text: &str) -> Result<Shard> {
        Shard::parse(text, |name| std::env::var(name).ok())
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
