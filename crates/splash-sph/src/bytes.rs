//! Byte counts as people write and read them (`12G`, `512M`; `1.23 GB`), for memory limits.

use std::fmt;

use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::error::{Error, Result, short_words};

/// A number of bytes; written in configs as `"8G"`, `"512M"` or a plain integer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct Bytes(pub u64);

impl Bytes {
    /// Parses a byte count as a user writes it: `12G`, `512M`, `1.5GB`, `800MiB`, `1000000`.
    /// Suffixes are binary (K = 1024).
    pub fn parse(text: &str) -> Result<Bytes> {
        let t = text.trim();
        let split = t.find(|c: char| c.is_ascii_alphabetic()).unwrap_or(t.len());
        let (number, unit) = t.split_at(split);
        let bad = || {
            let text = short_words(text);
            Error::config(format!(
                "'{text}' is not a size: use e.g. 12G, 512M or 1000000"
            ))
        };
        let number: f64 = number.trim().parse().map_err(|_| bad())?;
        let scale: u64 = match unit.trim().to_ascii_lowercase().as_str() {
            "" | "b" => 1,
            "k" | "kb" | "kib" => 1 << 10,
            "m" | "mb" | "mib" => 1 << 20,
            "g" | "gb" | "gib" => 1 << 30,
            "t" | "tb" | "tib" => 1 << 40,
            _ => {
                return Err(Error::config(short_words(&format!(
                    "'{text}': unknown unit '{unit}' (use K, M, G or T)"
                ))));
            }
        };
        if !(number.is_finite() && number >= 0.0) {
            return Err(bad());
        }
        Ok(Bytes((number * scale as f64) as u64))
    }
}

/// Bytes for people: `1.23 GB`, `45.6 MB` (decimal units, as the paper's tables).
pub fn human(bytes: u64) -> String {
    let b = bytes as f64;
    if b >= 1e9 {
        format!("{:.2} GB", b / 1e9)
    } else if b >= 1e6 {
        format!("{:.1} MB", b / 1e6)
    } else {
        format!("{:.0} kB", b / 1e3)
    }
}

impl fmt::Display for Bytes {
    /// In the largest binary unit that divides it (`8G`, `1536M`), else in bytes.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (shift, unit) in [(40, "T"), (30, "G"), (20, "M"), (10, "K")] {
            if self.0 != 0 && self.0.is_multiple_of(1 << shift) {
                return write!(f, "{}{unit}", self.0 >> shift);
            }
        }
        write!(f, "{}", self.0)
    }
}

impl Serialize for Bytes {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(&self.to_string())
    }
}

impl<'de> Deserialize<'de> for Bytes {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Raw {
            Number(u64),
            Text(String),
        }
        match Raw::deserialize(d)? {
            Raw::Number(v) => Ok(Bytes(v)),
            Raw::Text(t) => Bytes::parse(&t).map_err(serde::de::Error::custom),
        }
    }
}

/// Total memory of the machine in bytes (MemTotal of /proc/meminfo), if known.
pub(crate) fn machine_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    meminfo_field(&text, "MemTotal:")
}

/// The memory the process may use, as far as the system says: the smallest of its cgroup's
/// limit (v2 `memory.max`, v1 `memory.limit_in_bytes`, on its own group and every parent),
/// SLURM's allocation (`SLURM_MEM_PER_NODE`, or `SLURM_MEM_PER_CPU` × `SLURM_CPUS_ON_NODE`, in
/// MB) and the memory available now (MemAvailable of /proc/meminfo); None where none is known.
pub(crate) fn available_memory() -> Option<u64> {
    let read = |p: &std::path::Path| std::fs::read_to_string(p).ok();
    let cgroup = read("/proc/self/cgroup".as_ref())
        .and_then(|text| cgroup_limit(&text, "/sys/fs/cgroup".as_ref(), read));
    let slurm = slurm_limit(|k| std::env::var(k).ok());
    let free = read("/proc/meminfo".as_ref()).and_then(|t| meminfo_field(&t, "MemAvailable:"));
    [cgroup, slurm, free].into_iter().flatten().min()
}

/// The memory limit when none is configured: 80 % of the memory the process may use, as far as
/// the system says (the smallest of its cgroup's limit, SLURM's allocation and the memory
/// available now), or 8 GiB where nothing is known. Room is left for the particles, the output
/// and the allocator's own overhead, which the engines' estimates do not count.
pub fn default_limit() -> u64 {
    limit_from(available_memory())
}

/// 80 % of `available`, or 8 GiB when it is unknown.
pub(crate) fn limit_from(available: Option<u64>) -> u64 {
    available.map_or(8 << 30, |m| m / 5 * 4)
}

/// The smallest memory limit of the cgroups of a process whose `/proc/self/cgroup` reads
/// `proc_cgroup`, with the cgroup file systems mounted under `root` (`/sys/fs/cgroup`): v2
/// (`0::/path`, files `root/path/memory.max`, also at `root/unified/…`) and v1 (`N:memory:/path`,
/// `root/memory/path/memory.limit_in_bytes`). Every parent of the group is read too, and the
/// mount's own top (in a container the group's path is often the host's, and the mount shows
/// the container's group at the top). `max` and v1's "unlimited" (near 2⁶³) count as none.
pub(crate) fn cgroup_limit(
    proc_cgroup: &str,
    root: &std::path::Path,
    read: impl Fn(&std::path::Path) -> Option<String>,
) -> Option<u64> {
    let mut limits = Vec::new();
    for line in proc_cgroup.lines() {
        let mut parts = line.splitn(3, ':');
        let (Some(_), Some(controllers), Some(path)) = (parts.next(), parts.next(), parts.next())
        else {
            continue;
        };
        let (dirs, file): (Vec<std::path::PathBuf>, &str) = if controllers.is_empty() {
            (vec![root.to_path_buf(), root.join("unified")], "memory.max")
        } else if controllers.split(',').any(|c| c == "memory") {
            (vec![root.join("memory")], "memory.limit_in_bytes")
        } else {
            continue;
        };
        for dir in dirs {
            // The group and each parent, up to the mount's top.
            let mut group = std::path::PathBuf::from(path.trim().trim_start_matches('/'));
            loop {
                if let Some(v) = read(&dir.join(&group).join(file)).and_then(|t| parse_limit(&t)) {
                    limits.push(v);
                }
                if !group.pop() {
                    break;
                }
            }
        }
    }
    limits.into_iter().min()
}

/// A cgroup limit file's value: a byte count, or None for `max` and v1's page-rounded 2⁶³.
fn parse_limit(text: &str) -> Option<u64> {
    let v: u64 = text.trim().parse().ok()?;
    (v < 1 << 62).then_some(v)
}

/// SLURM's memory for this job step on this node, from its environment (`get`):
/// `SLURM_MEM_PER_NODE` MB, else `SLURM_MEM_PER_CPU` MB × `SLURM_CPUS_ON_NODE` (1 if unset).
/// A value of 0 (all the node's memory) counts as none.
pub(crate) fn slurm_limit(get: impl Fn(&str) -> Option<String>) -> Option<u64> {
    let mb = |k: &str| -> Option<u64> {
        let t = get(k)?;
        // SLURM writes plain MB; accept a unit suffix as sbatch's --mem does.
        let b = Bytes::parse(&t).ok()?.0;
        let b = if t.trim().bytes().all(|c| c.is_ascii_digit()) {
            b.checked_mul(1 << 20)?
        } else {
            b
        };
        (b > 0).then_some(b)
    };
    if let Some(node) = mb("SLURM_MEM_PER_NODE") {
        return Some(node);
    }
    let cpus = get("SLURM_CPUS_ON_NODE")
        .and_then(|c| c.trim().parse::<u64>().ok())
        .filter(|&c| c > 0)
        .unwrap_or(1);
    mb("SLURM_MEM_PER_CPU").and_then(|m| m.checked_mul(cpus))
}

/// A `Key:   N kB` line of /proc/meminfo, in bytes.
pub(crate) fn meminfo_field(text: &str, key: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(key))?;
    let kib: u64 = line[key.len()..].split_whitespace().next()?.parse().ok()?;
    kib.checked_mul(1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An error quotes the start of a long text only (found by tests/fuzz.rs).
    #[test]
    fn errors_quote_long_texts_short() {
        for text in [
            "9".repeat(5000) + "x",
            "x".repeat(5000),
            "1".to_string() + &"Q".repeat(5000),
        ] {
            let e = Bytes::parse(&text).unwrap_err().to_string();
            assert!(e.len() < 200, "{e}");
            assert!(e.contains("…"), "{e}");
        }
    }

    #[test]
    fn sizes_parse_and_print() {
        assert_eq!(Bytes::parse("1000").unwrap(), Bytes(1000));
        assert_eq!(Bytes::parse("2K").unwrap(), Bytes(2048));
        assert_eq!(Bytes::parse("1.5G").unwrap(), Bytes(3 << 29));
        assert_eq!(Bytes::parse("512MiB").unwrap(), Bytes(512 << 20));
        assert!(Bytes::parse("lots").is_err());
        assert!(Bytes::parse("3X").is_err());
        assert_eq!(Bytes(8 << 30).to_string(), "8G");
        assert_eq!(Bytes(1536 << 20).to_string(), "1536M");
        assert_eq!(Bytes(1000).to_string(), "1000");
    }

    #[test]
    fn cgroup_limits_are_the_smallest_of_the_group_and_its_parents() {
        use std::collections::HashMap;
        use std::path::Path;
        let files = |pairs: &[(&str, &str)]| -> HashMap<String, String> {
            pairs
                .iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect()
        };
        let limit = |cgroup: &str, fs: &HashMap<String, String>| {
            cgroup_limit(cgroup, Path::new("/cg"), |p| {
                fs.get(p.to_str().unwrap()).cloned()
            })
        };
        // v2: "max" is no limit; a parent's limit applies to its children.
        let v2 = files(&[
            ("/cg/job/step/memory.max", "max\n"),
            ("/cg/job/memory.max", "2147483648\n"),
            ("/cg/memory.max", "max"),
        ]);
        assert_eq!(limit("0::/job/step\n", &v2), Some(2 << 30));
        assert_eq!(limit("0::/\n", &v2), None);
        let own = files(&[
            ("/cg/job/memory.max", "1073741824"),
            ("/cg/memory.max", "4294967296"),
        ]);
        assert_eq!(limit("0::/job", &own), Some(1 << 30));
        // v1: the memory controller's line; the top of the mount where the group's own
        // directory is not visible (a container); 2⁶³ rounded to pages is no limit.
        let v1 = files(&[
            ("/cg/memory/memory.limit_in_bytes", "536870912\n"),
            (
                "/cg/memory/docker/abc/memory.limit_in_bytes",
                "9223372036854771712\n",
            ),
        ]);
        let text = "9:name=systemd:/\n4:memory:/docker/abc\n3:cpuset:/\n0::/\n";
        assert_eq!(limit(text, &v1), Some(512 << 20));
        let unlimited = files(&[("/cg/memory/memory.limit_in_bytes", "9223372036854771712")]);
        assert_eq!(limit("4:memory:/x", &unlimited), None);
        assert_eq!(limit("4:cpu,memory:/", &v1), Some(512 << 20));
        assert_eq!(limit("garbage", &v1), None);
    }

    #[test]
    fn slurm_memory_is_per_node_or_per_cpu_times_cpus() {
        let env = |pairs: &'static [(&'static str, &'static str)]| {
            move |k: &str| {
                pairs
                    .iter()
                    .find(|(n, _)| *n == k)
                    .map(|(_, v)| v.to_string())
            }
        };
        assert_eq!(slurm_limit(env(&[])), None);
        assert_eq!(
            slurm_limit(env(&[("SLURM_MEM_PER_NODE", "4000")])),
            Some(4000 << 20)
        );
        assert_eq!(
            slurm_limit(env(&[
                ("SLURM_MEM_PER_CPU", "1500"),
                ("SLURM_CPUS_ON_NODE", "4")
            ])),
            Some(6000 << 20)
        );
        assert_eq!(
            slurm_limit(env(&[("SLURM_MEM_PER_CPU", "1500")])),
            Some(1500 << 20)
        );
        assert_eq!(
            slurm_limit(env(&[
                ("SLURM_MEM_PER_NODE", "2G"),
                ("SLURM_MEM_PER_CPU", "100")
            ])),
            Some(2 << 30)
        );
        // 0 is "all of the node" to sbatch: no limit of its own.
        assert_eq!(slurm_limit(env(&[("SLURM_MEM_PER_NODE", "0")])), None);
        assert_eq!(slurm_limit(env(&[("SLURM_MEM_PER_NODE", "lots")])), None);
    }

    #[test]
    fn the_default_limit_is_four_fifths_of_what_is_available() {
        let meminfo = "MemTotal:       24684092 kB\nMemFree:        22456780 kB\nMemAvailable:   24229568 kB\n";
        assert_eq!(
            meminfo_field(meminfo, "MemAvailable:"),
            Some(24229568 * 1024)
        );
        assert_eq!(meminfo_field(meminfo, "Nope:"), None);
        assert_eq!(limit_from(Some(10 << 30)), 8 << 30);
        assert_eq!(limit_from(None), 8 << 30);
        let available = available_memory();
        if cfg!(target_os = "linux") {
            let a = available.unwrap();
            assert!(a > 1 << 20 && a <= machine_memory().unwrap());
            assert!(default_limit() < a);
        }
    }

    #[test]
    fn machine_memory_is_read() {
        if cfg!(target_os = "linux") {
            assert!(machine_memory().unwrap() > 1 << 20);
        }
    }
}
