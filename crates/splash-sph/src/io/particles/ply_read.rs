//! PLY particle input.
//!
//! ply_rs_bw parses the header; the payload is decoded here, because its payload reader builds a
//! map per element (far too slow for millions of particles) and preallocates from the untrusted
//! header count. Only the elements up to `vertex` are read: those before it are skipped, those
//! after it ignored. This module reads the header and the layout it declares; `ply_binary_read`
//! and `ply_ascii_read` read the payload.

use std::io::{BufRead, BufReader, Read};
use std::path::Path;

use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{DefaultElement, Encoding, Header};

use super::attribute_columns::AttributeColumns;
use super::failure::{Failure, Result};
use super::ply_layout::{Kind, Layout};
use super::{ply_ascii_read, ply_binary_read};
use crate::data::Particles;
use crate::io::text::lines::Lines;

/// Headers are a few hundred bytes; the cap keeps a non-PLY file from being read whole.
const MAX_HEADER_BYTES: u64 = 1 << 20;

/// Reads the `vertex` element's coordinates and every other scalar property of it as an
/// attribute (list properties are skipped).
pub(super) fn read(path: &Path) -> Result<Particles> {
    let (file, file_len) = super::failure::open_input(path)?;
    let mut reader = BufReader::with_capacity(1 << 16, file);
    let (header, header_len, header_lines) = read_header(&mut reader)?;
    let layout = Layout::new(&header)?;
    let vertex = &layout.vertex;
    let names: Vec<&str> = vertex.props.iter().map(|p| p.name.as_str()).collect();
    let scalar = |i: usize| matches!(vertex.props[i].kind, Kind::Scalar(_));
    let mut attributes = AttributeColumns::new(&names, layout.xyz_indices(), scalar, false);
    let columns = &mut attributes;
    let positions = match header.encoding {
        Encoding::Ascii => {
            let lines = Lines::new(reader, header_lines);
            ply_ascii_read::read(lines, &layout, columns, file_len.saturating_sub(header_len))
        }
        Encoding::BinaryLittleEndian => {
            ply_binary_read::read(&mut reader, &layout, columns, false, header_len, file_len)
        }
        Encoding::BinaryBigEndian => {
            ply_binary_read::read(&mut reader, &layout, columns, true, header_len, file_len)
        }
    }?;
    Ok(Particles {
        positions,
        attributes: attributes.into_map(),
    })
}

/// Reads the header up to `end_header`, returning it with its length in bytes and lines
/// (`mesh/ply_read` reads meshes' headers with it too).
pub(in crate::io) fn read_header(reader: &mut impl BufRead) -> Result<(Header, u64, usize)> {
    let mut bytes = Vec::new();
    let mut limited = (&mut *reader).take(MAX_HEADER_BYTES);
    limited
        .read_until(b'\n', &mut bytes)
        .map_err(|e| Failure::io("cannot read the header", e))?;
    if bytes.trim_ascii_end() != b"ply" {
        bail_format!("not a PLY file: the first line is not 'ply'");
    }
    let mut lines = 1;
    loop {
        let start = bytes.len();
        let n = limited
            .read_until(b'\n', &mut bytes)
            .map_err(|e| Failure::io("cannot read the header", e))?;
        if n == 0 {
            if bytes.len() as u64 >= MAX_HEADER_BYTES {
                bail_format!(
                    "malformed PLY header: no 'end_header' line in the first {MAX_HEADER_BYTES} bytes"
                );
            }
            bail_format!("malformed PLY header: the file ends before the 'end_header' line");
        }
        lines += 1;
        if bytes
            .get(start..)
            .is_some_and(|line| line.trim_ascii() == b"end_header")
        {
            break;
        }
    }
    check_header_lines(&bytes)?;
    let header = Parser::<DefaultElement>::new()
        .read_header(&mut Reader::new(bytes.as_slice()))
        .map_err(|e| {
            // The parser's message spans several indented lines and ends with a dump of the
            // grammar's expectations: keep the line number and text.
            let message = e.to_string();
            let message = message.split("\n\tError:").next().unwrap_or_default();
            let words: Vec<&str> = message.split_whitespace().collect();
            let message = words.join(" ");
            // The parser quotes the whole line, which may be a megabyte long: quote its start.
            let message = match message.split_once("String: '") {
                Some((head, line)) => {
                    let line = line.strip_suffix('\'').unwrap_or(line);
                    format!("{head}String: '{}'", super::failure::short(line))
                }
                None => super::failure::short_message(&message),
            };
            format_failure!("malformed PLY header: {message}")
        })?;
    if (header.version.major, header.version.minor) != (1, 0) {
        bail_format!(
            "PLY format version {}.{} is not supported: the only PLY version is 1.0",
            header.version.major,
            header.version.minor
        );
    }
    // The parser keeps the last of two same-named elements or properties in the first one's
    // place, which would silently shift the binary layout.
    let text = String::from_utf8_lossy(&bytes);
    let declared = |keyword| {
        text.lines()
            .filter(|line| line.split_ascii_whitespace().next() == Some(keyword))
            .count()
    };
    let properties: usize = header.elements.values().map(|e| e.properties.len()).sum();
    if declared("element") != header.elements.len() || declared("property") != properties {
        bail_format!(
            "malformed PLY header: two elements, or two properties of an element, have the same name"
        );
    }
    Ok((header, bytes.len() as u64, lines))
}

const SCALAR_TYPES: [&str; 16] = [
    "char", "uchar", "short", "ushort", "int", "uint", "float", "double", "int8", "uint8", "int16",
    "uint16", "int32", "uint32", "float32", "float64",
];

/// Says in words what is wrong with a header line, with its number and what was expected: the
/// parser's own messages ("Couldn't parse line") name the line but not the problem.
fn check_header_lines(header: &[u8]) -> Result<()> {
    let mut format = false;
    let mut element = false;
    for (i, line) in header.split(|&b| b == b'\n').enumerate().skip(1) {
        let n = i + 1;
        let Ok(line) = std::str::from_utf8(line) else {
            bail_format!("malformed PLY header: line {n} is not text (a PLY header is ASCII)");
        };
        if !line.is_ascii() {
            bail_format!(
                "malformed PLY header: line {n} ('{}') has non-ASCII characters (a PLY header \
                 is ASCII)",
                super::failure::short(line.trim())
            );
        }
        let words: Vec<&str> = line.split_ascii_whitespace().collect();
        let got = || super::failure::short(line.trim());
        match words.first().copied() {
            None if i + 1 < header.split(|&b| b == b'\n').count() - 1 => bail_format!(
                "malformed PLY header: line {n} is blank (a PLY header has no blank lines)"
            ),
            None | Some("comment" | "obj_info" | "end_header") => {}
            Some("format") => {
                let encodings = ["ascii", "binary_little_endian", "binary_big_endian"];
                if words.len() != 3
                    || !encodings.contains(&words[1])
                    || words[2].parse::<f32>().is_err()
                {
                    bail_format!(
                        "malformed PLY header: line {n} is '{}', expected 'format ascii 1.0', \
                         'format binary_little_endian 1.0' or 'format binary_big_endian 1.0'",
                        got()
                    );
                }
                format = true;
            }
            Some("element") => {
                if words.len() != 3 || words[2].parse::<u64>().is_err() {
                    bail_format!(
                        "malformed PLY header: line {n} is '{}', expected 'element NAME COUNT' \
                         with a whole number COUNT ('element vertex 1000')",
                        got()
                    );
                }
                element = true;
            }
            Some("property") => {
                let scalar = |t: &str| SCALAR_TYPES.contains(&t);
                let fine = match words.get(1).copied() {
                    Some("list") => words.len() == 5 && scalar(words[2]) && scalar(words[3]),
                    Some(t) => words.len() == 3 && scalar(t),
                    None => false,
                };
                if !fine {
                    bail_format!(
                        "malformed PLY header: line {n} is '{}', expected 'property TYPE NAME' \
                         ('property float x') or 'property list COUNT_TYPE TYPE NAME', TYPE a \
                         PLY scalar type (char, uchar, short, int, float, double, int8 … float64)",
                        got()
                    );
                }
                if !element {
                    bail_format!(
                        "malformed PLY header: line {n} declares a property before any \
                         'element' line"
                    );
                }
            }
            Some(word) => bail_format!(
                "malformed PLY header: line {n} starts with '{}', expected one of format, \
                 comment, obj_info, element, property, end_header",
                super::failure::short(word)
            ),
        }
    }
    if !format {
        bail_format!(
            "malformed PLY header: no 'format' line (such as 'format binary_little_endian 1.0')"
        );
    }
    Ok(())
}
