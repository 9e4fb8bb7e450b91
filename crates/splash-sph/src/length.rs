//! Lengths in units of the particle spacing r ("2r", "r/2") or in world units (Akinci et al.
//! 2012 Sec. 3 gives cells, supports and the band in units of r).

use std::fmt;

use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::error::{Error, Result, short_words};

/// A length either in multiples of the particle spacing r ("2r", "r", "r/2", "0.5r") or in
/// world units (a plain number).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Length {
    /// Multiples of the particle spacing r.
    Spacings(f32),
    /// World units.
    World(f32),
}

impl Length {
    /// The length in world units for spacing `r`.
    pub fn resolve(self, r: f32) -> f32 {
        match self {
            Length::Spacings(k) => k * r,
            Length::World(l) => l,
        }
    }

    /// Errors unless the length is positive and finite, naming `key`.
    pub fn check_positive(self, key: &str) -> Result<()> {
        positive(key, self.value())
    }

    /// The number as written, in units of r or world units.
    pub fn value(self) -> f32 {
        match self {
            Length::Spacings(v) | Length::World(v) => v,
        }
    }

    /// `2r`, `r`, `0.5r`, `r/2`, `r/4`, `3r/2` (any `Kr/N`) or a plain number (world units).
    pub fn parse(text: &str) -> Result<Length> {
        let t = text.trim();
        let bad = || {
            let text = short_words(text);
            Error::config(format!(
                "'{text}' is not a length: use e.g. 2r, r, r/2, r/4, 0.5r or 0.007"
            ))
        };
        let number = |s: &str| s.trim().parse::<f32>().map_err(|_| bad());
        let (head, divisor) = match t.split_once("r/") {
            Some((head, n)) => (head, number(n)?),
            None => match t.strip_suffix('r') {
                Some(head) => (head, 1.0),
                None => return number(t).map(Length::World),
            },
        };
        if !(divisor.is_finite() && divisor > 0.0) {
            return Err(bad());
        }
        let k = if head.is_empty() { 1.0 } else { number(head)? };
        Ok(Length::Spacings(k / divisor))
    }
}

impl fmt::Display for Length {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Length::Spacings(1.0) => write!(f, "r"),
            Length::Spacings(0.5) => write!(f, "r/2"),
            Length::Spacings(k) => write!(f, "{k}r"),
            Length::World(l) => write!(f, "{l}"),
        }
    }
}

impl Serialize for Length {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        match *self {
            Length::World(l) => s.serialize_f32(l),
            Length::Spacings(_) => s.serialize_str(&self.to_string()),
        }
    }
}

impl<'de> Deserialize<'de> for Length {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Raw {
            Number(f64),
            Text(String),
        }
        match Raw::deserialize(d)? {
            Raw::Number(v) => Ok(Length::World(v as f32)),
            Raw::Text(t) => Length::parse(&t).map_err(serde::de::Error::custom),
        }
    }
}

/// Errors unless `v` is a positive, finite length, naming `key`.
pub(crate) fn positive(key: &str, v: f32) -> Result<()> {
    if !(v.is_finite() && v > 0.0) {
        return Err(Error::config(format!(
            "{key} must be a positive length, got {v}"
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An error quotes the start of a long text only (found by tests/fuzz.rs).
    #[test]
    fn errors_quote_long_texts_short() {
        for text in [
            "9".repeat(5000) + "x",
            "2r".to_string() + &" ".repeat(5000) + "x",
            "x".repeat(5000),
            "1".to_string() + &"Q".repeat(5000),
        ] {
            let e = Length::parse(&text).unwrap_err().to_string();
            assert!(e.len() < 200, "{e}");
            assert!(e.contains("…"), "{e}");
        }
    }

    #[test]
    fn lengths_parse() {
        assert_eq!(Length::parse("2r").unwrap(), Length::Spacings(2.0));
        assert_eq!(Length::parse("r").unwrap(), Length::Spacings(1.0));
        assert_eq!(Length::parse("r/2").unwrap(), Length::Spacings(0.5));
        assert_eq!(Length::parse("0.25r").unwrap(), Length::Spacings(0.25));
        assert_eq!(Length::parse("r/4").unwrap(), Length::Spacings(0.25));
        assert_eq!(Length::parse(" 3r/2 ").unwrap(), Length::Spacings(1.5));
        assert_eq!(Length::parse("r/3").unwrap(), Length::Spacings(1.0 / 3.0));
        assert_eq!(Length::parse("r/2.5").unwrap(), Length::Spacings(0.4));
        assert_eq!(Length::parse("0.007").unwrap(), Length::World(0.007));
        for bad in [
            "half", "r/", "r/0", "r/-2", "r/x", "xr/2", "r/2r", "2", "r r",
        ] {
            let parsed = Length::parse(bad);
            assert!(parsed.is_err() || bad == "2", "{bad} parsed as {parsed:?}");
        }
        assert_eq!(Length::parse("2").unwrap(), Length::World(2.0));
    }
}
