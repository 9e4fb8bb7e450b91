//! Text-table particle input (CSV and friends); the accepted dialect is documented on
//! [`super::read_particles`].

use std::io::BufReader;
use std::path::Path;

use glam::Vec3;

use super::failure::Result;
use super::lines::Lines;

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

/// Which columns hold the coordinates, and what to call them in messages.
struct Columns {
    index: [usize; 3],
    names: [String; 3],
}

const COORDINATES: [[&str; 3]; 1] = [["x", "y", "z"]];
/// The velocity columns splash reads, in order of preference.
const VELOCITIES: [[&str; 3]; 2] = [
    ["vx", "vy", "vz"],
    ["velocity_x", "velocity_y", "velocity_z"],
];

pub(super) fn read(path: &Path) -> Result<Vec<Vec3>> {
    read_triples(path, &COORDINATES, true)
}

/// Reads the velocities: the first of [`VELOCITIES`] the header names; a header is required.
pub(super) fn read_velocities(path: &Path) -> Result<Vec<Vec3>> {
    read_triples(path, &VELOCITIES, false)
}

/// Reads three columns per row as a point: the first of `candidates` whose first column the
/// header names, or the first three columns when there is no header and `headerless` allows.
fn read_triples(path: &Path, candidates: &[[&str; 3]], headerless: bool) -> Result<Vec<Vec3>> {
    let (file, file_len) = super::open_input(path)?;
    let mut lines = Lines::new(BufReader::with_capacity(1 << 16, file), 0);
    let mut particles = Vec::new();
    let mut layout: Option<(Separator, Columns)> = None;
    while let Some((line, text)) = lines.next_non_blank()? {
        let text = text.trim_start_matches('\u{feff}');
        if text.is_empty() || text.starts_with('#') {
            continue;
        }
        let (separator, columns) = match &layout {
            Some((separator, columns)) => (*separator, columns),
            None => {
                let separator = Separator::detect(text);
                let is_header = separator.fields(text).any(|f| f.parse::<f32>().is_err());
                let columns = if is_header {
                    header_columns(separator, text, line, candidates)?
                } else if !headerless {
                    bail_format!(
                        "line {line}: the table has no header, so it names no {} columns",
                        candidates[0].join(", ")
                    );
                } else {
                    Columns {
                        index: [0, 1, 2],
                        names: ["x", "y", "z"].map(String::from),
                    }
                };
                // Typical lines are 20-40 bytes; the file size bounds the estimate.
                particles.reserve(usize::try_from(file_len / 32).unwrap_or(0));
                let (separator, columns) = layout.insert((separator, columns));
                if is_header {
                    continue;
                }
                (*separator, &*columns)
            }
        };
        let p = parse_row(separator, text, columns, line)?;
        particles.push(super::finite(p, || format!("line {line}"))?);
    }
    Ok(particles)
}

/// Finds the columns of the first of `candidates` whose first column the header line names.
fn header_columns(
    separator: Separator,
    text: &str,
    line: usize,
    candidates: &[[&str; 3]],
) -> Result<Columns> {
    let names: Vec<&str> = separator.fields(text).collect();
    let has = |wanted: &str| names.iter().any(|n| n.eq_ignore_ascii_case(wanted));
    let chosen = match candidates.iter().find(|c| has(c[0])) {
        Some(chosen) => *chosen,
        None if candidates.len() == 1 => candidates[0],
        None => {
            let wanted: Vec<String> = candidates.iter().map(|c| c.join(", ")).collect();
            bail_format!(
                "line {line}: the header has none of the columns {} (its columns: {})",
                wanted.join(" or "),
                names.join(", ")
            );
        }
    };
    let mut index = [0; 3];
    for (slot, wanted) in index.iter_mut().zip(chosen) {
        *slot = names
            .iter()
            .position(|name| name.eq_ignore_ascii_case(wanted))
            .ok_or_else(|| {
                format_failure!(
                    "line {line} is taken as a header (not all its fields are numbers), but it has \
                     no column '{wanted}' (its columns: {})",
                    names.join(", ")
                )
            })?;
    }
    Ok(Columns {
        index,
        names: index.map(|i| names.get(i).copied().unwrap_or_default().to_owned()),
    })
}

/// Parses the coordinates from data row `line`.
fn parse_row(separator: Separator, text: &str, columns: &Columns, line: usize) -> Result<Vec3> {
    let mut coordinates = [None; 3];
    let last = columns.index.iter().copied().max().unwrap_or_default();
    let mut found = 0;
    for (i, field) in separator.fields(text).enumerate().take(last + 1) {
        found = i + 1;
        for ((slot, &wanted), name) in coordinates
            .iter_mut()
            .zip(&columns.index)
            .zip(&columns.names)
        {
            if wanted == i {
                let value = field.parse::<f32>().map_err(|_| {
                    format_failure!(
                        "line {line}, column {} ('{name}'): '{field}' is not a number",
                        i + 1
                    )
                })?;
                *slot = Some(value);
            }
        }
    }
    let [Some(x), Some(y), Some(z)] = coordinates else {
        let missing = columns
            .index
            .iter()
            .zip(&columns.names)
            .filter(|&(&i, _)| i >= found);
        let missing: Vec<String> = missing
            .map(|(i, name)| format!("column {} ('{name}')", i + 1))
            .collect();
        bail_format!(
            "line {line}: the row has only {found} columns; missing {}",
            missing.join(", ")
        );
    };
    Ok(Vec3::new(x, y, z))
}
