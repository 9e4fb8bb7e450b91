//! Legacy VTK input (`.vtk`), ascii or binary (big-endian, as the format prescribes): the
//! points of a `POLYDATA`, `UNSTRUCTURED_GRID` or `STRUCTURED_GRID` data set and every
//! `POINT_DATA` array (`SCALARS`, `VECTORS`, `NORMALS`, `TEXTURE_COORDINATES`, `TENSORS`,
//! `COLOR_SCALARS` and the arrays of a `FIELD`). Cells, cell data and field data of the data
//! set are read past and dropped, except a mesh's triangles ([`parse_mesh`]). File versions up
//! to 5.1 (`OFFSETS`/`CONNECTIVITY` cells).

use super::failure::Result;
use super::failure::short;
use super::point_arrays::{self, Num, PointArray};
use crate::data::Particles;

pub(super) fn read(path: &std::path::Path) -> Result<Particles> {
    parse(&point_arrays::read_all(path)?)
}

struct Cursor<'a> {
    data: &'a [u8],
    pos: usize,
    binary: bool,
}

/// Where the arrays that follow belong.
#[derive(Clone, Copy, PartialEq)]
enum Section {
    /// Before `POINT_DATA`/`CELL_DATA`: a `FIELD` here is the data set's field data.
    None,
    Point,
    Cell(usize),
}

pub(super) fn parse(data: &[u8]) -> Result<Particles> {
    parse_any(data, false).map(|(points, _)| points)
}

/// A `POLYDATA` mesh: its points, point data (the normals are still the array `Normals`) and
/// `POLYGONS`, which must be triangles; other cells are refused.
pub(in crate::io) fn parse_mesh(data: &[u8]) -> Result<(Particles, Vec<[u32; 3]>)> {
    parse_any(data, true)
}

/// The points and point data, and, if `mesh`, the triangles.
fn parse_any(data: &[u8], mesh: bool) -> Result<(Particles, Vec<[u32; 3]>)> {
    let mut triangles = Vec::new();
    let mut c = Cursor {
        data,
        pos: 0,
        binary: false,
    };
    let (_, first) = c.raw_line();
    if !first.trim_start().starts_with("# vtk DataFile") {
        bail_format!(
            "not a legacy VTK file: the first line must be '# vtk DataFile Version …', found '{}'",
            short(first.trim())
        );
    }
    c.raw_line(); // the title
    let (at, encoding) = c.line()?;
    c.binary = match encoding.trim().to_ascii_uppercase().as_str() {
        "ASCII" => false,
        "BINARY" => true,
        other => bail_format!(
            "line 3 (byte offset {at}) must be ASCII or BINARY, found '{}'",
            short(other)
        ),
    };
    let mut positions: Option<Vec<f32>> = None;
    let mut arrays = Vec::new();
    let mut section = Section::None;
    let mut point_count = None;
    let mut dataset = false;
    while let Some((at, line)) = c.next_line() {
        let words: Vec<&str> = line.split_whitespace().collect();
        let keyword = words[0].to_ascii_uppercase();
        let arg = |i: usize| -> Result<&str> {
            words.get(i).copied().ok_or_else(|| {
                format_failure!(
                    "'{}' at byte offset {at} is missing its argument {i}",
                    short(line)
                )
            })
        };
        let count = |i: usize| -> Result<usize> {
            let word = arg(i)?;
            word.parse::<usize>().map_err(|_| {
                format_failure!(
                    "'{}' at byte offset {at}: '{}' is not a count",
                    short(line),
                    short(word)
                )
            })
        };
        match keyword.as_str() {
            "DATASET" => {
                let kind = arg(1)?.to_ascii_uppercase();
                if !matches!(
                    kind.as_str(),
                    "POLYDATA" | "UNSTRUCTURED_GRID" | "STRUCTURED_GRID"
                ) {
                    bail_format!(
                        "the data set at byte offset {at} is {}, not a point set: splash reads \
                         POLYDATA, UNSTRUCTURED_GRID and STRUCTURED_GRID",
                        short(&kind)
                    );
                }
                if mesh && kind != "POLYDATA" {
                    bail_format!(
                        "the data set at byte offset {at} is {}: a mesh is POLYDATA",
                        short(&kind)
                    );
                }
                dataset = true;
            }
            "DIMENSIONS" => {}
            "POINTS" => {
                if positions.is_some() {
                    bail_format!("a second POINTS at byte offset {at}");
                }
                let n = count(1)?;
                let num = num_type(arg(2)?, at)?;
                positions = Some(c.values(n, 3, num, at)?);
                point_count = Some(n);
            }
            "POLYGONS" if mesh => {
                let (n, size) = (count(1)?, count(2)?);
                triangles = c.polygons(n, size, at)?;
            }
            "VERTICES" | "LINES" | "TRIANGLE_STRIPS" | "CELLS" if mesh && count(1)? > 0 => {
                bail_format!("{keyword} at byte offset {at}: a mesh has triangles (POLYGONS) only")
            }
            "VERTICES" | "LINES" | "POLYGONS" | "TRIANGLE_STRIPS" | "CELLS" => {
                let (n, size) = (count(1)?, count(2)?);
                if c.peek_keyword().as_deref() == Some("OFFSETS") {
                    // Version 5: n offsets, then `size` connectivity entries.
                    for (part, len) in [("OFFSETS", n), ("CONNECTIVITY", size)] {
                        let (at, num) = c.array_header(part)?;
                        c.skip_values(len, num, at)?;
                    }
                } else {
                    c.skip_values(size, Num::I32, at)?;
                }
            }
            "CELL_TYPES" => c.skip_values(count(1)?, Num::I32, at)?,
            "METADATA" => c.skip_metadata(),
            "POINT_DATA" => {
                let n = count(1)?;
                if Some(n) != point_count {
                    bail_format!(
                        "POINT_DATA at byte offset {at} is for {n} points, but the data set has {}",
                        point_count.map_or("no POINTS before it".into(), |n| format!("{n} points"))
                    );
                }
                section = Section::Point;
            }
            "CELL_DATA" => section = Section::Cell(count(1)?),
            "FIELD" => {
                let arrays_in_field = count(2)?;
                for _ in 0..arrays_in_field {
                    let (at, line) = c.line()?;
                    let words: Vec<&str> = line.split_whitespace().collect();
                    if words
                        .first()
                        .is_some_and(|w| w.eq_ignore_ascii_case("METADATA"))
                    {
                        c.skip_metadata();
                        continue;
                    }
                    if words.first() == Some(&"NULL_ARRAY") {
                        continue;
                    }
                    let [name, width, tuples, ty] = words[..] else {
                        bail_format!(
                            "expected a field array 'name components tuples type' at byte \
                             offset {at}, found '{}'",
                            short(line)
                        );
                    };
                    let parse = |w: &str| {
                        w.parse::<usize>().map_err(|_| {
                            format_failure!(
                                "'{}' at byte offset {at}: '{}' is not a count",
                                short(line),
                                short(w)
                            )
                        })
                    };
                    let (width, tuples) = (parse(width)?, parse(tuples)?);
                    let num = num_type(ty, at)?;
                    let values = c.values(tuples, width, num, at)?;
                    if section == Section::Point {
                        if Some(tuples) != point_count {
                            bail_format!(
                                "point data array '{}' at byte offset {at} has {tuples} tuples \
                                 for {} points",
                                short(name),
                                point_count.unwrap_or(0)
                            );
                        }
                        arrays.push(PointArray {
                            name: name.to_owned(),
                            width,
                            values,
                        });
                    }
                }
            }
            "SCALARS"
            | "VECTORS"
            | "NORMALS"
            | "TENSORS"
            | "TEXTURE_COORDINATES"
            | "COLOR_SCALARS" => {
                let tuples = match section {
                    Section::Point => point_count.unwrap_or(0),
                    Section::Cell(n) => n,
                    Section::None => bail_format!(
                        "{keyword} at byte offset {at} comes before POINT_DATA or CELL_DATA"
                    ),
                };
                let name = arg(1)?;
                let (width, num) = match keyword.as_str() {
                    "SCALARS" => {
                        let width = match words.get(3) {
                            Some(_) => count(3)?,
                            None => 1,
                        };
                        (width, num_type(arg(2)?, at)?)
                    }
                    "TEXTURE_COORDINATES" => (count(2)?, num_type(arg(3)?, at)?),
                    "COLOR_SCALARS" => (count(2)?, if c.binary { Num::U8 } else { Num::F32 }),
                    "TENSORS" => (9, num_type(arg(2)?, at)?),
                    _ => (3, num_type(arg(2)?, at)?),
                };
                if keyword == "SCALARS" && c.peek_keyword().as_deref() == Some("LOOKUP_TABLE") {
                    c.line()?;
                }
                let mut values = c.values(tuples, width, num, at)?;
                if keyword == "COLOR_SCALARS" && c.binary {
                    values.iter_mut().for_each(|v| *v /= 255.0);
                }
                if section == Section::Point {
                    arrays.push(PointArray {
                        name: name.to_owned(),
                        width,
                        values,
                    });
                }
            }
            "LOOKUP_TABLE" => {
                let num = if c.binary { Num::U8 } else { Num::F32 };
                c.skip_values(count(2)?.saturating_mul(4), num, at)?;
            }
            _ => bail_format!(
                "unknown or unsupported keyword '{}' at byte offset {at}",
                short(words[0])
            ),
        }
    }
    if !dataset {
        bail_format!("the file has no DATASET line");
    }
    let Some(positions) = positions else {
        bail_format!("the data set has no POINTS");
    };
    Ok((point_arrays::particles(&positions, arrays)?, triangles))
}

fn num_type(name: &str, at: usize) -> Result<Num> {
    Ok(match name.to_ascii_lowercase().as_str() {
        "char" => Num::I8,
        "unsigned_char" => Num::U8,
        "short" => Num::I16,
        "unsigned_short" => Num::U16,
        "int" | "vtktypeint32" => Num::I32,
        "unsigned_int" | "vtktypeuint32" => Num::U32,
        "long" | "vtktypeint64" | "vtkidtype" => Num::I64,
        "unsigned_long" | "vtktypeuint64" => Num::U64,
        "float" => Num::F32,
        "double" => Num::F64,
        other => bail_format!(
            "unsupported data type '{}' at byte offset {at}",
            short(other)
        ),
    })
}

impl<'a> Cursor<'a> {
    /// The next line, blank or not, without its line end; empty at the end of the data.
    fn raw_line(&mut self) -> (usize, &'a str) {
        let start = self.pos;
        let rest = &self.data[start..];
        let end = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
        self.pos = (start + end + 1).min(self.data.len());
        let line = &rest[..end];
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        (start, std::str::from_utf8(line).unwrap_or("\u{fffd}"))
    }

    /// The next non-blank line, or `None` at the end of the data.
    fn next_line(&mut self) -> Option<(usize, &'a str)> {
        while self.pos < self.data.len() {
            let (at, line) = self.raw_line();
            if !line.trim().is_empty() {
                return Some((at, line));
            }
        }
        None
    }

    fn line(&mut self) -> Result<(usize, &'a str)> {
        let end = self.data.len();
        self.next_line().ok_or_else(|| {
            format_failure!("the file ends (byte offset {end}) where a line was expected")
        })
    }

    /// The first word of the next non-blank line, upper case, without consuming it.
    /// The header line of a version-5 cell array (`OFFSETS vtktypeint64`): where it is and the
    /// number type of its values.
    fn array_header(&mut self, part: &str) -> Result<(usize, Num)> {
        let (at, line) = self.line()?;
        let mut words = line.split_whitespace();
        if !words.next().is_some_and(|w| w.eq_ignore_ascii_case(part)) {
            bail_format!(
                "expected {part} at byte offset {at}, found '{}'",
                short(line)
            );
        }
        Ok((at, num_type(words.next().unwrap_or(""), at)?))
    }

    fn peek_keyword(&self) -> Option<String> {
        let mut probe = Cursor {
            data: self.data,
            pos: self.pos,
            binary: self.binary,
        };
        let (_, line) = probe.next_line()?;
        Some(line.split_whitespace().next()?.to_ascii_uppercase())
    }

    /// Lines up to the next blank one (a `METADATA` block).
    fn skip_metadata(&mut self) {
        while self.pos < self.data.len() {
            if self.raw_line().1.trim().is_empty() {
                break;
            }
        }
    }

    /// `tuples × width` values of type `num`, as `f32`; `at` is the offset of the header line.
    fn values(&mut self, tuples: usize, width: usize, num: Num, at: usize) -> Result<Vec<f32>> {
        let n = tuples.saturating_mul(width);
        let remaining = self.data.len() - self.pos;
        if self.binary {
            let bytes = n.saturating_mul(num.size());
            if bytes > remaining {
                bail_format!(
                    "truncated binary data: the array declared at byte offset {at} ({tuples} × \
                     {width} values of {} bytes) needs {bytes} bytes from byte offset {}, but the \
                     file ends at byte offset {}",
                    num.size(),
                    self.pos,
                    self.data.len()
                );
            }
            let mut out = Vec::with_capacity(n);
            num.decode_into(&self.data[self.pos..self.pos + bytes], true, &mut out);
            self.pos += bytes;
            Ok(out)
        } else {
            // Each value takes at least one character and a separator.
            if n > remaining / 2 + 1 {
                bail_format!(
                    "the array declared at byte offset {at} has {n} values, more than the rest of \
                     the file ({remaining} bytes) can hold"
                );
            }
            let mut out = Vec::with_capacity(n);
            for _ in 0..n {
                let (start, token) = self.token();
                if token.is_empty() {
                    bail_format!(
                        "the file ends after {} of the {n} values declared at byte offset {at}",
                        out.len()
                    );
                }
                let text = std::str::from_utf8(token).unwrap_or("\u{fffd}");
                let value = match num {
                    Num::F32 | Num::F64 => text.parse::<f64>().ok().map(|v| v as f32),
                    _ => text.parse::<i128>().ok().map(|v| v as f32),
                };
                match value {
                    Some(v) => out.push(v),
                    None => bail_format!(
                        "'{}' at byte offset {start} is not a number (value {} of {n} declared at \
                         byte offset {at})",
                        short(text),
                        out.len()
                    ),
                }
            }
            Ok(out)
        }
    }

    /// `POLYGONS n size`, all triangles: `size` ints of `3 a b c` each (file versions before
    /// 5), or `OFFSETS` and `CONNECTIVITY` arrays (version 5).
    fn polygons(&mut self, n: usize, size: usize, at: usize) -> Result<Vec<[u32; 3]>> {
        let not_triangles = || format_failure!("POLYGONS at byte offset {at}: not all triangles");
        let corners = if self.peek_keyword().as_deref() == Some("OFFSETS") {
            let mut arrays = Vec::with_capacity(2);
            for (part, len) in [("OFFSETS", n), ("CONNECTIVITY", size)] {
                let (at, num) = self.array_header(part)?;
                arrays.push(self.indices(len, num, at)?);
            }
            // n offsets bound n − 1 polygons: 0, 3, 6, …
            let offsets = &arrays[0];
            if (0..n).any(|k| offsets[k] != 3 * k as u64) || size != 3 * n.saturating_sub(1) {
                return Err(not_triangles());
            }
            arrays.swap_remove(1)
        } else {
            if size != n.saturating_mul(4) {
                return Err(not_triangles());
            }
            let values = self.indices(size, Num::I32, at)?;
            if values.chunks_exact(4).any(|p| p[0] != 3) {
                return Err(not_triangles());
            }
            values
                .chunks_exact(4)
                .flat_map(|p| [p[1], p[2], p[3]])
                .collect()
        };
        let index = |i: u64| u32::try_from(i).map_err(|_| not_triangles());
        corners
            .chunks_exact(3)
            .map(|t| Ok([index(t[0])?, index(t[1])?, index(t[2])?]))
            .collect()
    }

    /// `n` values of type `num` as vertex numbers, exactly: negative or fractional values are
    /// refused.
    fn indices(&mut self, n: usize, num: Num, at: usize) -> Result<Vec<u64>> {
        let bad =
            || format_failure!("the array at byte offset {at} holds a value that is not an index");
        if self.binary {
            let bytes = n.saturating_mul(num.size());
            if bytes > self.data.len() - self.pos {
                bail_format!(
                    "truncated binary data: the array declared at byte offset {at} needs {bytes}                      bytes from byte offset {}, but the file ends at byte offset {}",
                    self.pos,
                    self.data.len()
                );
            }
            let block = &self.data[self.pos..self.pos + bytes];
            self.pos += bytes;
            block
                .chunks_exact(num.size())
                .map(|b| num.to_index(b, true).ok_or_else(bad))
                .collect()
        } else {
            if n > (self.data.len() - self.pos) / 2 + 1 {
                bail_format!(
                    "the array declared at byte offset {at} has {n} values, more than the rest of                      the file can hold"
                );
            }
            (0..n)
                .map(|_| {
                    let (_, token) = self.token();
                    let text = std::str::from_utf8(token).ok();
                    text.and_then(|t| t.parse::<u64>().ok()).ok_or_else(bad)
                })
                .collect()
        }
    }

    fn skip_values(&mut self, n: usize, num: Num, at: usize) -> Result<()> {
        if self.binary {
            let bytes = n.saturating_mul(num.size());
            if bytes > self.data.len() - self.pos {
                bail_format!(
                    "truncated binary data: the block declared at byte offset {at} needs {bytes} \
                     bytes from byte offset {}, but the file ends at byte offset {}",
                    self.pos,
                    self.data.len()
                );
            }
            self.pos += bytes;
        } else {
            for i in 0..n {
                if self.token().1.is_empty() {
                    bail_format!(
                        "the file ends after {i} of the {n} values declared at byte offset {at}"
                    );
                }
            }
        }
        Ok(())
    }

    /// The next whitespace-separated token and its offset; empty at the end of the data.
    fn token(&mut self) -> (usize, &'a [u8]) {
        let data = self.data;
        while self.pos < data.len() && data[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        let start = self.pos;
        while self.pos < data.len() && !data[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        (start, &data[start..self.pos])
    }
}
