//! Text-table particle input (CSV and friends); the accepted dialect is documented on
//! [`super::read_particles`].

use std::io::BufReader;
use std::path::Path;

use glam::Vec3;

use super::attribute_columns::AttributeColumns;
use super::failure::Result;
use crate::data::Particles;
use crate::io::text::lines::Lines;

#[derive(Clone, Copy)]
enum Separator {
    Comma,
    Semicolon,
    Whitespace,
}

impl Separator {
    fn detect(line: &str) -> Self {
        if line.contains(',') {
            Self::Comma
        } else if line.contains(';') {
            Self::Semicolon
        } else {
            Self::Whitespace
        }
    }

    /// The line's fields, trimmed and unquoted. Runs of whitespace separate one field, while
    /// two adjacent commas enclose an empty one.
    fn fields(self, line: &str) -> impl Iterator<Item = &str> {
        match self {
            Self::Comma => Fields::Char(line.split(',')),
            Self::Semicolon => Fields::Char(line.split(';')),
            Self::Whitespace => Fields::Whitespace(line.split_ascii_whitespace()),
        }
        .map(unquote)
    }
}

/// Splits on a character, or on whitespace; both are much faster than splitting with a closure.
enum Fields<'a> {
    Char(std::str::Split<'a, char>),
    Whitespace(std::str::SplitAsciiWhitespace<'a>),
}

impl<'a> Iterator for Fields<'a> {
    type Item = &'a str;

    fn next(&mut self) -> Option<&'a str> {
        match self {
            Self::Char(fields) => fields.next(),
            Self::Whitespace(fields) => fields.next(),
        }
    }
}

fn unquote(field: &str) -> &str {
    let field = field.trim();
    field
        .strip_prefix('"')
        .and_then(|f| f.strip_suffix('"'))
        .map_or(field, str::trim)
}

/// The table's layout, as its first line declares it.
struct Table {
    separator: Separator,
    /// The columns of `x`, `y`, `z`.
    xyz: [usize; 3],
    /// The header's column names; `x y z` without a header.
    names: Vec<String>,
    has_header: bool,
}

impl Table {
    /// Reads the layout from the first line, `text`: a header if any of its fields is not a
    /// number.
    fn new(text: &str, line: usize) -> Result<Self> {
        let separator = Separator::detect(text);
        let has_header = separator.fields(text).any(|f| f.parse::<f32>().is_err());
        if !has_header {
            return Ok(Self {
                separator,
                xyz: [0, 1, 2],
                names: ["x", "y", "z"].map(String::from).to_vec(),
                has_header,
            });
        }
        let names: Vec<&str> = separator.fields(text).collect();
        let mut xyz = [0; 3];
        for (slot, wanted) in xyz.iter_mut().zip(["x", "y", "z"]) {
            *slot = names
                .iter()
                .position(|name| name.eq_ignore_ascii_case(wanted))
                .ok_or_else(|| {
                    format_failure!(
                        "line {line} is taken as a header (not all its fields are numbers), but it \
                         has no column '{wanted}' (its columns: {})",
                        super::failure::listed(names.iter().copied())
                    )
                })?;
            let columns = names
                .iter()
                .filter(|n| n.eq_ignore_ascii_case(wanted))
                .count();
            if columns > 1 {
                bail_format!(
                    "line {line}: the header names column '{wanted}' {columns} times; which one \
                     holds the coordinate?"
                );
            }
        }
        Ok(Self {
            separator,
            xyz,
            names: names.into_iter().map(String::from).collect(),
            has_header,
        })
    }

    /// The attribute columns: those the header names, other than the coordinates, that are
    /// `numeric`.
    fn attributes(&self, numeric: impl Fn(usize) -> bool) -> AttributeColumns {
        if !self.has_header {
            return AttributeColumns::none();
        }
        let names: Vec<&str> = self.names.iter().map(String::as_str).collect();
        AttributeColumns::new(&names, self.xyz, numeric, true)
    }
}

/// Reads the coordinates of every row and, if the table has a header, every column that holds a
/// number in the first row as an attribute (every later row must then hold a number there).
pub(super) fn read(path: &Path) -> Result<Particles> {
    let (file, file_len) = super::failure::open_input(path)?;
    let mut lines = Lines::new(BufReader::with_capacity(1 << 16, file), 0);
    let mut particles = Vec::new();
    let mut table: Option<Table> = None;
    let mut attributes: Option<AttributeColumns> = None;
    while let Some((line, text)) = lines.next_non_blank()? {
        let text = text.trim_start_matches('\u{feff}');
        if text.is_empty() || text.starts_with('#') {
            continue;
        }
        let table = match &table {
            Some(table) => table,
            None => {
                let new = table.insert(Table::new(text, line)?);
                if new.has_header {
                    continue;
                }
                new
            }
        };
        let attributes = match &mut attributes {
            Some(attributes) => attributes,
            None => {
                let fields: Vec<&str> = table.separator.fields(text).collect();
                let numeric = |i: usize| fields.get(i).is_some_and(|f| f.parse::<f32>().is_ok());
                let attributes = attributes.insert(table.attributes(numeric));
                // Rows like the first fill the file: an estimate, bounded by the file's size.
                let rows = usize::try_from(file_len / (text.len() as u64 + 1)).unwrap_or(0);
                particles.reserve(rows);
                attributes.reserve(rows);
                attributes
            }
        };
        let p = parse_row(table, attributes, text, line)?;
        particles.push(super::failure::finite(p, || format!("line {line}"))?);
    }
    let attributes = match (attributes, table) {
        (Some(attributes), _) => attributes,
        // A header without rows: its columns are attributes without values.
        (None, Some(table)) => table.attributes(|_| true),
        (None, None) => AttributeColumns::none(),
    };
    Ok(Particles {
        positions: particles,
        attributes: attributes.into_map(),
    })
}

/// Parses data row `line`: the coordinates, returned, and the attributes, appended.
fn parse_row(
    table: &Table,
    attributes: &mut AttributeColumns,
    text: &str,
    line: usize,
) -> Result<Vec3> {
    let mut coordinates = [0.0; 3];
    let last = table.xyz.iter().copied().max().unwrap_or_default();
    let last = last.max(attributes.last());
    let name = |i: usize| table.names.get(i).map_or("", String::as_str);
    attributes.push();
    let mut found = 0;
    for (i, field) in table.separator.fields(text).enumerate().take(last + 1) {
        found = i + 1;
        let coordinate = table.xyz.iter().position(|&c| c == i);
        if coordinate.is_none() && !attributes.reads(i) {
            continue;
        }
        let value = field.parse::<f32>().map_err(|_| {
            format_failure!(
                "line {line}, column {} ('{}'): '{}' is not a number",
                i + 1,
                super::failure::short(name(i)),
                super::failure::short(field)
            )
        })?;
        match coordinate {
            Some(c) => coordinates[c] = value,
            None => attributes.set_last(i, value),
        }
    }
    if found <= last {
        let missing = (found..=last).filter(|&i| table.xyz.contains(&i) || attributes.reads(i));
        let missing: Vec<usize> = missing.collect();
        let shown: Vec<String> = missing
            .iter()
            .take(4)
            .map(|&i| format!("column {} ('{}')", i + 1, super::failure::short(name(i))))
            .collect();
        let more = match missing.len().saturating_sub(shown.len()) {
            0 => String::new(),
            n => format!(" and {n} more"),
        };
        bail_format!(
            "line {line}: the row has only {found} columns; missing {}{more}",
            shown.join(", ")
        );
    }
    Ok(Vec3::from_array(coordinates))
}
