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
pub fn machine_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line["MemTotal:".len()..]
        .split_whitespace()
        .next()?
        .parse()
        .ok()?;
    Some(kib * 1024)
}

/// The memory limit when none is configured: half the machine's memory, or 8 GiB where that
/// is unknown.
pub fn default_limit() -> u64 {
    machine_memory().map_or(8 << 30, |m| m / 2)
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
    fn machine_memory_is_read() {
        if cfg!(target_os = "linux") {
            assert!(machine_memory().unwrap() > 1 << 20);
        }
    }
}
