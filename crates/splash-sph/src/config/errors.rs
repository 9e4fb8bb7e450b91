//! Configuration errors that point at the offending key's line of the TOML text.
//!
//! toml points its own errors at the key or value, except inside `[field]`: serde reads that
//! internally tagged enum (`kind` picks the variant) by buffering the table first, which loses
//! the keys' positions, so every error in it pointed at the table's header. [`parse_error`]
//! reads the table again with its kind known, straight from the text. Range errors of
//! [`Config::validate`](crate::Config::validate) come after parsing, when positions are gone;
//! their messages start with the dotted key (`field.t_low (4) must be …`), which
//! [`validation_error`] finds in the text.

use std::ops::Range;

use serde::Deserialize;
use serde::de::value::MapAccessDeserializer;
use serde::de::{self, DeserializeSeed, Deserializer, IgnoredAny, IntoDeserializer, MapAccess};

use crate::error::short_words;
use crate::field::FieldConfig;

/// `error`, or when it lies inside `[field]`, the same error pointing at its key or value.
pub(crate) fn parse_error(text: &str, error: toml::de::Error) -> toml::de::Error {
    match field_error(text) {
        // The same message means the same failure, found again with its position.
        Some(located) if located.message() == error.message() => located,
        _ => error,
    }
}

/// The error of reading the `[field]` table as the struct of its kind, if there is one.
fn field_error(text: &str) -> Option<toml::de::Error> {
    #[derive(Deserialize)]
    struct Document {
        field: Option<Kind>,
    }
    #[derive(Deserialize)]
    struct Kind {
        kind: String,
    }
    let kind = toml::from_str::<Document>(text).ok()?.field?.kind;
    let document = toml::de::Deserializer::parse(text).ok()?;
    document.deserialize_map(FieldOf(&kind)).err()
}

/// Reads a document's `[field]` table as the struct of field kind `.0`, skipping the rest.
struct FieldOf<'a>(&'a str);

impl<'de> de::Visitor<'de> for FieldOf<'_> {
    type Value = ();

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a table")
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        while let Some(key) = map.next_key::<String>()? {
            if key == "field" {
                map.next_value_seed(FieldTable(self.0))?;
            } else {
                map.next_value::<IgnoredAny>()?;
            }
        }
        Ok(())
    }
}

/// The `[field]` table of one kind, as a seed.
struct FieldTable<'a>(&'a str);

impl<'de> DeserializeSeed<'de> for FieldTable<'_> {
    type Value = ();

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_map(FieldEntries(self.0))
    }
}

struct FieldEntries<'a>(&'a str);

impl<'de> de::Visitor<'de> for FieldEntries<'_> {
    type Value = ();

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("the [field] table")
    }

    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<(), A::Error> {
        FieldConfig::deserialize_kind(self.0, MapAccessDeserializer::new(WithoutKind(map)))
            .map(drop)
    }
}

/// A table's entries without its `kind`, each key and value still read from the text, so that
/// toml gives every error the position of the key or value it arose in.
struct WithoutKind<A>(A);

impl<'de, A: MapAccess<'de>> MapAccess<'de> for WithoutKind<A> {
    type Error = A::Error;

    fn next_key_seed<K: DeserializeSeed<'de>>(
        &mut self,
        seed: K,
    ) -> Result<Option<K::Value>, A::Error> {
        let mut seed = seed;
        loop {
            match self.0.next_key_seed(KeyUnlessKind(seed))? {
                None => return Ok(None),
                Some(Key::Other(key)) => return Ok(Some(key)),
                Some(Key::Kind(unused)) => {
                    self.0.next_value::<IgnoredAny>()?;
                    seed = unused;
                }
            }
        }
    }

    fn next_value_seed<V: DeserializeSeed<'de>>(&mut self, seed: V) -> Result<V::Value, A::Error> {
        self.0.next_value_seed(seed)
    }
}

enum Key<S, V> {
    /// The `kind` key, and the seed for the next one.
    Kind(S),
    Other(V),
}

/// Reads a key with seed `.0`, unless it is `kind`. The seed runs inside toml's reading of the
/// key, which gives its errors (an unknown key) the key's position.
struct KeyUnlessKind<S>(S);

impl<'de, S: DeserializeSeed<'de>> DeserializeSeed<'de> for KeyUnlessKind<S> {
    type Value = Key<S, S::Value>;

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<Self::Value, D::Error> {
        d.deserialize_str(self)
    }
}

impl<'de, S: DeserializeSeed<'de>> de::Visitor<'de> for KeyUnlessKind<S> {
    type Value = Key<S, S::Value>;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a key")
    }

    fn visit_str<E: de::Error>(self, key: &str) -> Result<Self::Value, E> {
        if key == "kind" {
            Ok(Key::Kind(self.0))
        } else {
            self.0.deserialize(key.into_deserializer()).map(Key::Other)
        }
    }
}

/// The message of a [`Config::validate`](crate::Config::validate) error on `text`, pointing at
/// the first key it names that the text sets, in the layout of toml's errors.
pub(crate) fn validation_error(text: &str, message: &str) -> String {
    let message = &short_words(message);
    let span = message
        .split(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == '.'))
        .map(|word| word.trim_matches('.'))
        .find_map(|word| value_span(text, word));
    match span {
        Some(span) => format!(
            "invalid configuration at {}\n{message}",
            snippet(text, span)
        ),
        None => format!("invalid configuration: {message}"),
    }
}

/// Where the text sets the value of the dotted key `path`.
fn value_span(text: &str, path: &str) -> Option<Range<usize>> {
    let document = toml::de::DeTable::parse(text).ok()?;
    let mut table = document.get_ref();
    let mut keys = path.split('.').peekable();
    while let Some(key) = keys.next() {
        let (_, value) = table.iter().find(|(k, _)| k.get_ref() == key)?;
        if keys.peek().is_none() {
            return Some(value.span());
        }
        match value.get_ref() {
            toml::de::DeValue::Table(t) => table = t,
            _ => return None,
        }
    }
    None
}

/// A toml parse error on `text` in toml's layout, but with a long line shown around the error
/// only and long words cut: toml quotes the whole line, and the whole of an unknown key.
pub(crate) fn render_parse_error(text: &str, error: &toml::de::Error) -> String {
    let message = short_words(error.message().trim_end());
    match error
        .span()
        .filter(|s| s.start <= s.end && s.end <= text.len())
    {
        Some(span) if text.is_char_boundary(span.start) && text.is_char_boundary(span.end) => {
            format!("TOML parse error at {}\n{message}", snippet(text, span))
        }
        _ => format!("TOML parse error: {message}"),
    }
}

/// Characters of a line on either side of the error that are shown.
const QUOTED: usize = 40;

/// `line L, column C` and the line with `span` underlined, as toml shows its errors; of a long
/// line, [`QUOTED`] characters on either side of the span.
fn snippet(text: &str, span: Range<usize>) -> String {
    let start = text[..span.start].rfind('\n').map_or(0, |i| i + 1);
    let end = text[span.start..]
        .find('\n')
        .map_or(text.len(), |i| span.start + i);
    let line = text[start..end].trim_end_matches('\r');
    let number = text[..start].matches('\n').count() + 1;
    let column = text[start..span.start].chars().count();
    let width = text[span.start..span.end.min(end)].chars().count().max(1);
    let gutter = " ".repeat(number.to_string().len() + 1);
    // The part of the line shown: from QUOTED characters before the span to QUOTED after it.
    let first = column.saturating_sub(QUOTED);
    let width = width.min(QUOTED);
    let shown: String = line
        .chars()
        .skip(first)
        .take(column - first + width + QUOTED)
        .collect();
    let (before, after) = (
        if first > 0 { "…" } else { "" },
        if line.chars().count() > column + width + QUOTED {
            "…"
        } else {
            ""
        },
    );
    let caret = column - first + before.chars().count();
    format!(
        "line {number}, column {}\n{gutter}|\n{number} | {before}{shown}{after}\n{gutter}|{}{}",
        column + 1,
        " ".repeat(caret + 1),
        "^".repeat(width)
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Config;

    /// The first line of `text`'s configuration error, and the line it points at.
    fn error(text: &str) -> (String, String) {
        let e = Config::from_toml(text).unwrap_err().to_string();
        let mut lines = e.lines();
        let first = lines.next().unwrap().to_owned();
        (first, lines.nth(1).unwrap_or_default().to_owned())
    }

    #[test]
    fn errors_inside_the_field_table_point_at_their_key() {
        let head = "spacing = 0.014\n\n[field]\nkind = \"ssp07\"\n\n";
        for (body, line, shown) in [
            ("t_lw = 4.0\n", 6, "6 | t_lw = 4.0"),
            ("radius = \"r\"\nt_low = \"x\"\n", 7, "7 | t_low = \"x\""),
            ("support = \"2x\"\n", 6, "6 | support = \"2x\""),
        ] {
            let (first, pointed) = error(&format!("{head}{body}"));
            assert!(first.contains(&format!("line {line}, column")), "{first}");
            assert_eq!(pointed, shown);
        }
        // `kind` after the other keys, and a dotted key.
        let (first, pointed) = error("[field]\nsupport = 1\nblobbiness = 2\nkind = \"zb05\"\n");
        assert!(first.contains("line 3, column 1"), "{first}");
        assert_eq!(pointed, "3 | blobbiness = 2");
        let (first, _) = error("field.kind = \"zb05\"\nfield.t_lo = 1\n");
        assert!(first.contains("line 2, column 7"), "{first}");
        // Errors outside [field] were right already, and stay so.
        let (first, pointed) = error("[band]\n\nhalf_wdth = \"2r\"\n");
        assert!(first.contains("line 3, column 1"), "{first}");
        assert_eq!(pointed, "3 | half_wdth = \"2r\"");
    }

    /// Errors on a long line show it around the error, and long names and values are cut: toml
    /// quoted the whole line and the whole of an unknown key (found by tests/fuzz.rs).
    #[test]
    fn errors_on_long_lines_stay_short() {
        let long = "a".repeat(5000);
        for text in [
            format!("[field]\nkind = \"ssp07\"\nkind {long}\n"),
            format!("spacing = 0.014 {long}\n"),
            format!("{long} = 1\n"),
            format!("cell = \"{long}\"\n"),
            format!("[output]\nformat = \"{long}\"\n"),
            format!("threads = 0 # {long}\nspacing = 1\n\n"),
        ] {
            let e = Config::from_toml(&text).unwrap_err().to_string();
            assert!(e.chars().count() < 600, "{} characters: {e}", e.len());
            assert!(e.contains("line "), "{e}");
        }
        let (first, pointed) = error(&format!("spacing = 0.014 {long}\n"));
        assert_eq!(first, "TOML parse error at line 1, column 11");
        assert!(pointed.starts_with("1 | spacing = 0.014 aaa"), "{pointed}");
        assert!(pointed.ends_with("a…"), "{pointed}");
    }

    #[test]
    fn range_errors_point_at_the_key_they_name() {
        let e = Config::from_toml("spacing = 0.014\n[field]\nkind = \"ssp07\"\n\nt_low = 4.0\n")
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "invalid configuration at line 5, column 9\n  |\n5 | t_low = 4.0\n  |         ^^^\n\
             field.t_low (4) must be below field.t_high (3.5)"
        );
        for (text, line) in [
            ("[slices]\n\nblock = 0\n", "3 | block = 0"),
            ("threads = 0\n", "1 | threads = 0"),
            ("spacing = 0.014\ncorrect = 33\n", "2 | correct = 33"),
            ("spacing = 0.01\n\ncell = 0.5\n", "3 | cell = 0.5"),
            (
                "[surface_particles]\ncolour_threshold = -1\n",
                "2 | colour_threshold = -1",
            ),
            // t_low is the default: the key that the text sets is pointed at.
            (
                "[field]\nkind = \"ssp07\"\nt_high = 0.1\n",
                "3 | t_high = 0.1",
            ),
        ] {
            let (first, pointed) = error(text);
            assert!(
                first.starts_with("invalid configuration at line"),
                "{first}"
            );
            assert_eq!(pointed, line);
        }
        // No key of the message in the text: the message alone.
        assert_eq!(
            validation_error("", "threads must be at least 1"),
            "invalid configuration: threads must be at least 1"
        );
    }
}
