//! VTK XML input (`.vtu`, `.vtp`): the points and every `PointData` array of each `Piece` of
//! an `UnstructuredGrid` or `PolyData` file, in any data mode: `ascii`, inline `binary`
//! (base64) and `appended` (raw or base64), each uncompressed or in zlib-compressed blocks
//! (`vtkZLibDataCompressor`), with `UInt32` or `UInt64` headers, either byte order. Cells and
//! cell data are not read for particles; [`parse_mesh`] reads a mesh's triangles.
//!
//! Hand-written on quick-xml, base64 and flate2: raw appended data is not XML, so the XML
//! part before `<AppendedData>` is parsed and the binary part addressed by offset. Every size
//! read from the file is checked against the bytes that hold it before anything is allocated;
//! a compressed block must inflate to exactly the size its header gives.

use std::path::Path;

use base64::Engine;
use quick_xml::events::{BytesStart, Event};

use super::failure::Result;
use super::failure::short;
use super::point_arrays::{self, Num, PointArray};
use crate::data::Particles;

/// Deflate inflates at most about 1032:1; more in a header is a lie.
const MAX_DEFLATE_RATIO: usize = 1032;

pub(super) fn read(path: &Path) -> Result<Particles> {
    parse(&point_arrays::read_all(path)?)
}

#[derive(Clone, Copy, PartialEq)]
enum Format {
    Ascii,
    Binary,
    Appended,
}

struct ArraySpec {
    name: String,
    num: Num,
    width: usize,
    format: Format,
    offset: usize,
    /// Where its tag starts, for messages.
    at: usize,
    /// The element's text (ascii and inline binary).
    text: Vec<u8>,
}

struct Piece {
    points: usize,
    /// `NumberOfCells` (`.vtu`) or `NumberOfPolys` (`.vtp`), for [`parse_mesh`].
    cells: usize,
    positions: Option<ArraySpec>,
    arrays: Vec<ArraySpec>,
    /// The `Cells` or `Polys` arrays, when asked for.
    cell_arrays: Vec<ArraySpec>,
}

struct File<'a> {
    big_endian: bool,
    header64: bool,
    compressed: bool,
    /// The appended data after its `_`, and whether it is base64.
    appended: Option<(&'a [u8], bool)>,
    /// Every appended array's offset, sorted: a base64 array ends where the next begins.
    offsets: Vec<usize>,
}

fn attr(tag: &BytesStart, name: &[u8]) -> Option<String> {
    tag.attributes()
        .flatten()
        .find(|a| a.key.as_ref().as_bytes() == name)
        .map(|a| a.value.to_string())
}

fn find(data: &[u8], needle: &[u8]) -> Option<usize> {
    data.windows(needle.len()).position(|w| w == needle)
}

pub(super) fn parse(data: &[u8]) -> Result<Particles> {
    let (file, pieces) = parse_pieces(data, false)?;
    particles(&file, pieces)
}

/// A mesh's one piece: its points and point data (the normals are still the array `Normals`)
/// and its triangles: `.vtu` cells of type 5 (triangle), `.vtp` polygons of 3 corners.
pub(in crate::io) fn parse_mesh(data: &[u8]) -> Result<(Particles, Vec<[u32; 3]>)> {
    let (file, mut pieces) = parse_pieces(data, true)?;
    if pieces.len() != 1 {
        bail_format!("expected one Piece, found {}", pieces.len());
    }
    let cells = pieces[0].cells;
    let arrays = std::mem::take(&mut pieces[0].cell_arrays);
    let points = particles(&file, pieces)?;
    let named = |name: &str| arrays.iter().find(|a| a.name == name);
    let triangles = match (named("connectivity"), named("offsets")) {
        (Some(connectivity), Some(offsets)) => {
            let ends = file.indices(offsets, cells)?;
            if let Some(k) = (0..cells).find(|&k| ends[k] != 3 * (k as u64 + 1)) {
                bail_format!("cell {k} is not a triangle (its offsets are not 3 apart)");
            }
            if let Some(types) = named("types") {
                let types = file.indices(types, cells)?;
                if let Some(k) = types.iter().position(|&t| t != 5) {
                    bail_format!("cell {k} is of type {}, not a triangle (5)", types[k]);
                }
            }
            let corners = file.indices(connectivity, cells.saturating_mul(3))?;
            let mut triangles = Vec::with_capacity(cells);
            for (k, c) in corners.chunks_exact(3).enumerate() {
                let index = |i: u64| u32::try_from(i).ok();
                match (index(c[0]), index(c[1]), index(c[2])) {
                    (Some(a), Some(b), Some(c)) => triangles.push([a, b, c]),
                    _ => bail_format!("cell {k} refers to a vertex number beyond 32 bits"),
                }
            }
            triangles
        }
        _ if cells == 0 => Vec::new(),
        _ => bail_format!("the piece has {cells} cells but no 'connectivity' and 'offsets' arrays"),
    };
    Ok((points, triangles))
}

/// The file's pieces, with their cell arrays if `cells`.
fn parse_pieces(data: &[u8], cells: bool) -> Result<(File<'_>, Vec<Piece>)> {
    let appended_tag = find(data, b"<AppendedData");
    let xml = &data[..appended_tag.unwrap_or(data.len())];
    let mut appended = None;
    if let Some(start) = appended_tag {
        let close = data[start..]
            .iter()
            .position(|&b| b == b'>')
            .map(|i| start + i)
            .ok_or_else(|| {
                format_failure!("the AppendedData tag at byte offset {start} is not closed")
            })?;
        let tag = String::from_utf8_lossy(&data[start..close]);
        let base64 = !tag.contains("\"raw\"");
        let underscore = data[close..]
            .iter()
            .position(|&b| b == b'_')
            .map(|i| close + i + 1)
            .ok_or_else(|| {
                format_failure!(
                    "the AppendedData at byte offset {start} has no '_' before its data"
                )
            })?;
        let mut body = &data[underscore..];
        if base64 {
            let end = find(body, b"</AppendedData").unwrap_or(body.len());
            body = &body[..end];
        }
        appended = Some((body, base64));
    }

    let mut reader = quick_xml::Reader::from_reader(xml);
    let mut file = File {
        big_endian: false,
        header64: false,
        compressed: false,
        appended,
        offsets: Vec::new(),
    };
    let mut pieces: Vec<Piece> = Vec::new();
    let mut seen_root = false;
    // Where DataArray elements are: "Points", "PointData" or elsewhere.
    let mut context: Vec<Vec<u8>> = Vec::new();
    let mut current: Option<(ArraySpec, bool)> = None;
    // Elements open inside the current DataArray (VTK's InformationKey): their text is not data.
    let mut nested = 0usize;
    loop {
        let at = reader.buffer_position() as usize;
        let event = match reader.read_event() {
            Ok(e) => e,
            // Without the appended data the XML is cut before its closing tags.
            Err(_) if file.appended.is_some() && at + 64 >= xml.len() => break,
            Err(e) => bail_format!(
                "malformed XML near byte offset {at}: {}",
                super::failure::short_message(&e.to_string())
            ),
        };
        let empty = matches!(event, Event::Empty(_));
        match event {
            Event::Start(tag) | Event::Empty(tag) => {
                let name = tag.name().as_ref().as_bytes().to_vec();
                match name.as_slice() {
                    b"VTKFile" => {
                        seen_root = true;
                        let kind = attr(&tag, b"type").unwrap_or_default();
                        if kind != "UnstructuredGrid" && kind != "PolyData" {
                            bail_format!(
                                "the VTK XML file is of type '{}': splash reads UnstructuredGrid \
                                 (.vtu) and PolyData (.vtp)",
                                short(&kind)
                            );
                        }
                        file.big_endian = attr(&tag, b"byte_order").as_deref() == Some("BigEndian");
                        file.header64 = match attr(&tag, b"header_type").as_deref() {
                            None | Some("UInt32") => false,
                            Some("UInt64") => true,
                            Some(other) => {
                                bail_format!("unsupported header_type '{}'", short(other))
                            }
                        };
                        file.compressed = match attr(&tag, b"compressor").as_deref() {
                            None | Some("") => false,
                            Some("vtkZLibDataCompressor") => true,
                            Some(other) => bail_format!(
                                "unsupported compressor '{}': splash reads uncompressed and \
                                 zlib-compressed (vtkZLibDataCompressor) data",
                                short(other)
                            ),
                        };
                    }
                    b"Piece" => {
                        let points = attr(&tag, b"NumberOfPoints").unwrap_or_default();
                        let points = points.trim().parse::<usize>().map_err(|_| {
                            format_failure!(
                                "the Piece at byte offset {at} has NumberOfPoints '{}', not a count",
                                short(&points)
                            )
                        })?;
                        let cell_count = attr(&tag, b"NumberOfCells")
                            .or_else(|| attr(&tag, b"NumberOfPolys"))
                            .unwrap_or_default();
                        let cell_count = match cell_count.trim() {
                            "" => 0,
                            count => count.parse::<usize>().map_err(|_| {
                                format_failure!(
                                    "the Piece at byte offset {at} has '{}' cells, not a count",
                                    short(count)
                                )
                            })?,
                        };
                        pieces.push(Piece {
                            points,
                            cells: cell_count,
                            positions: None,
                            arrays: Vec::new(),
                            cell_arrays: Vec::new(),
                        });
                    }
                    b"DataArray" => {
                        let spec = array_spec(&tag, at)?;
                        if spec.format == Format::Appended {
                            file.offsets.push(spec.offset);
                        }
                        let wanted = match context.last().map(Vec::as_slice) {
                            Some(b"Points" | b"PointData") => true,
                            Some(b"Cells" | b"Polys") => cells,
                            _ => false,
                        } && !pieces.is_empty();
                        if empty {
                            finish(&mut pieces, &context, spec, wanted)?;
                        } else {
                            current = Some((spec, wanted));
                        }
                    }
                    _ => {}
                }
                if !empty && name != b"DataArray" {
                    if current.is_some() {
                        nested += 1;
                    }
                    context.push(name);
                }
            }
            Event::Text(text) => {
                if let (Some((spec, true)), 0) = (&mut current, nested) {
                    spec.text.extend_from_slice(text.as_ref().as_bytes());
                }
            }
            Event::End(tag) => {
                if tag.name().as_ref().as_bytes() == b"DataArray" {
                    if let Some((spec, wanted)) = current.take() {
                        finish(&mut pieces, &context, spec, wanted)?;
                    }
                } else {
                    nested = nested.saturating_sub(1);
                    context.pop();
                }
            }
            Event::Eof => {
                if let (Some(open), None) = (context.last(), file.appended) {
                    bail_format!(
                        "malformed XML: the file ends (byte offset {at}) inside <{}>",
                        short(&String::from_utf8_lossy(open))
                    );
                }
                break;
            }
            _ => {}
        }
    }
    if !seen_root {
        bail_format!("not a VTK XML file: no VTKFile element");
    }
    file.offsets.sort_unstable();
    file.offsets.dedup();
    Ok((file, pieces))
}

/// The points and point data of every piece.
fn particles(file: &File, pieces: Vec<Piece>) -> Result<Particles> {
    let mut positions = Vec::new();
    let mut columns: Vec<PointArray> = Vec::new();
    let total: usize = pieces
        .iter()
        .map(|p| p.points)
        .fold(0, usize::saturating_add);
    for (index, piece) in pieces.into_iter().enumerate() {
        let Some(spec) = piece.positions else {
            if piece.points == 0 {
                continue;
            }
            bail_format!(
                "Piece {index} has {} points but no Points array",
                piece.points
            );
        };
        if spec.width != 3 {
            bail_format!(
                "the Points array at byte offset {} has {} components, not 3",
                spec.at,
                spec.width
            );
        }
        positions.extend(file.values(&spec, piece.points)?);
        for spec in piece.arrays {
            let values = file.values(&spec, piece.points)?;
            match columns
                .iter_mut()
                .find(|c| c.name == spec.name && c.width == spec.width)
            {
                Some(column) => column.values.extend(values),
                None if index == 0 => columns.push(PointArray {
                    name: spec.name,
                    width: spec.width,
                    values,
                }),
                None => {}
            }
        }
    }
    // An array missing from a later piece cannot be a per-particle attribute.
    columns.retain(|c| c.values.len() == c.width * total);
    point_arrays::particles(&positions, columns)
}

fn array_spec(tag: &BytesStart, at: usize) -> Result<ArraySpec> {
    let ty = attr(tag, b"type").unwrap_or_default();
    let num = match ty.as_str() {
        "Int8" => Num::I8,
        "UInt8" => Num::U8,
        "Int16" => Num::I16,
        "UInt16" => Num::U16,
        "Int32" => Num::I32,
        "UInt32" => Num::U32,
        "Int64" => Num::I64,
        "UInt64" => Num::U64,
        "Float32" => Num::F32,
        "Float64" => Num::F64,
        other => bail_format!(
            "the DataArray at byte offset {at} has unsupported type '{}'",
            short(other)
        ),
    };
    let width = match attr(tag, b"NumberOfComponents") {
        None => 1,
        Some(w) => match w.trim().parse::<usize>() {
            Ok(w) if (1..=1024).contains(&w) => w,
            _ => bail_format!(
                "the DataArray at byte offset {at} has NumberOfComponents '{}'",
                short(&w)
            ),
        },
    };
    let format = match attr(tag, b"format").as_deref() {
        Some("ascii") => Format::Ascii,
        Some("binary") => Format::Binary,
        Some("appended") => Format::Appended,
        other => bail_format!(
            "the DataArray at byte offset {at} has format '{}': expected ascii, binary or appended",
            short(other.unwrap_or(""))
        ),
    };
    let offset = match (format, attr(tag, b"offset")) {
        (Format::Appended, Some(o)) => o.trim().parse::<usize>().map_err(|_| {
            format_failure!(
                "the DataArray at byte offset {at} has offset '{}'",
                short(&o)
            )
        })?,
        (Format::Appended, None) => {
            bail_format!("the appended DataArray at byte offset {at} has no offset")
        }
        _ => 0,
    };
    Ok(ArraySpec {
        name: attr(tag, b"Name").unwrap_or_default(),
        num,
        width,
        format,
        offset,
        at,
        text: Vec::new(),
    })
}

fn finish(pieces: &mut [Piece], context: &[Vec<u8>], spec: ArraySpec, wanted: bool) -> Result<()> {
    if !wanted {
        return Ok(());
    }
    let Some(piece) = pieces.last_mut() else {
        return Ok(());
    };
    match context.last().map(Vec::as_slice) {
        Some(b"Points") if piece.positions.is_none() => piece.positions = Some(spec),
        Some(b"Points") => bail_format!("a second Points array at byte offset {}", spec.at),
        Some(b"Cells" | b"Polys") => piece.cell_arrays.push(spec),
        _ => piece.arrays.push(spec),
    }
    Ok(())
}

/// An array's content: its text (ascii), or its `n` values' bytes (decoded and inflated).
enum Data<'s> {
    Text(&'s [u8]),
    Binary(&'s [u8]),
}

impl File<'_> {
    /// The array's `points × width` values as `f32`.
    fn values(&self, spec: &ArraySpec, points: usize) -> Result<Vec<f32>> {
        let n = points.saturating_mul(spec.width);
        self.with_data(spec, n, |data, what| match data {
            Data::Text(text) => ascii(text, n, spec.num, what),
            Data::Binary(raw) => {
                let mut out = Vec::with_capacity(n);
                spec.num.decode_into(raw, self.big_endian, &mut out);
                Ok(out)
            }
        })
    }

    /// The array's `n` values as vertex numbers, exactly (negative and fractional values are
    /// refused).
    fn indices(&self, spec: &ArraySpec, n: usize) -> Result<Vec<u64>> {
        let bad = |what: &str| format_failure!("{what}: a value is not a vertex or cell number");
        self.with_data(spec, n, |data, what| match data {
            Data::Text(text) => {
                let words = text
                    .split(u8::is_ascii_whitespace)
                    .filter(|w| !w.is_empty());
                let values: Option<Vec<u64>> = words
                    .map(|w| std::str::from_utf8(w).ok()?.parse::<u64>().ok())
                    .collect();
                match values {
                    Some(v) if v.len() == n => Ok(v),
                    Some(v) => bail_format!("{what}: {} values, but {n} declared", v.len()),
                    None => Err(bad(what)),
                }
            }
            Data::Binary(raw) => {
                let size = spec.num.size();
                let values: Option<Vec<u64>> = raw
                    .chunks_exact(size)
                    .map(|c| spec.num.to_index(c, self.big_endian))
                    .collect();
                values.ok_or_else(|| bad(what))
            }
        })
    }

    /// Calls `f` with the array's text or bytes, for `n` values, and a name for messages.
    fn with_data<T>(
        &self,
        spec: &ArraySpec,
        n: usize,
        f: impl FnOnce(Data, &str) -> Result<T>,
    ) -> Result<T> {
        let what = &format!(
            "array '{}' (DataArray at byte offset {})",
            short(&spec.name),
            spec.at
        );
        match spec.format {
            Format::Ascii => f(Data::Text(&spec.text), what),
            Format::Binary => {
                let bytes = decode_base64(&spec.text, what)?;
                f(Data::Binary(&self.binary(&bytes, n, spec.num, what)?), what)
            }
            Format::Appended => {
                let Some((body, base64)) = self.appended else {
                    bail_format!("{what} is appended, but the file has no AppendedData");
                };
                if spec.offset > body.len() {
                    bail_format!(
                        "{what} starts at offset {} of the appended data, which has {} bytes",
                        spec.offset,
                        body.len()
                    );
                }
                if base64 {
                    let end = self
                        .offsets
                        .iter()
                        .find(|&&o| o > spec.offset)
                        .map_or(body.len(), |&o| o.min(body.len()));
                    let bytes = decode_base64(&body[spec.offset..end], what)?;
                    f(Data::Binary(&self.binary(&bytes, n, spec.num, what)?), what)
                } else {
                    let raw = self.binary(&body[spec.offset..], n, spec.num, what)?;
                    f(Data::Binary(&raw), what)
                }
            }
        }
    }

    fn header_value(&self, bytes: &[u8], index: usize, what: &str) -> Result<usize> {
        let size = if self.header64 { 8 } else { 4 };
        let Some(b) = bytes.get(index * size..(index + 1) * size) else {
            bail_format!(
                "{what}: its binary data ends inside its header ({} bytes)",
                bytes.len()
            );
        };
        // Through u64, not f32: sizes must be exact.
        let value = if self.header64 {
            let a: [u8; 8] = b.try_into().unwrap_or([0; 8]);
            if self.big_endian {
                u64::from_be_bytes(a)
            } else {
                u64::from_le_bytes(a)
            }
        } else {
            let a: [u8; 4] = b.try_into().unwrap_or([0; 4]);
            u64::from(if self.big_endian {
                u32::from_be_bytes(a)
            } else {
                u32::from_le_bytes(a)
            })
        };
        usize::try_from(value)
            .map_err(|_| format_failure!("{what}: header value {value} is too large"))
    }

    /// The data bytes of `n` values after the header, inflated if compressed (`bytes` may run
    /// on past the array's end).
    fn binary<'b>(
        &self,
        bytes: &'b [u8],
        n: usize,
        num: Num,
        what: &str,
    ) -> Result<std::borrow::Cow<'b, [u8]>> {
        let expected = n.saturating_mul(num.size());
        let hsize = if self.header64 { 8 } else { 4 };
        let raw: std::borrow::Cow<[u8]> = if !self.compressed {
            let len = self.header_value(bytes, 0, what)?;
            if len != expected {
                bail_format!(
                    "{what}: its header gives {len} bytes of data, but {n} values of {} bytes are \
                     {expected}",
                    num.size()
                );
            }
            let data = &bytes[hsize..];
            if data.len() < len {
                bail_format!(
                    "{what}: truncated binary data: {len} bytes declared, {} present",
                    data.len()
                );
            }
            std::borrow::Cow::Borrowed(&data[..len])
        } else {
            std::borrow::Cow::Owned(self.inflate(bytes, expected, what)?)
        };
        Ok(raw)
    }

    /// The zlib blocks of one array: header `blocks, block size, last block size, compressed
    /// sizes…`, then the blocks; the total must be `expected` bytes.
    fn inflate(&self, bytes: &[u8], expected: usize, what: &str) -> Result<Vec<u8>> {
        let hsize = if self.header64 { 8 } else { 4 };
        let blocks = self.header_value(bytes, 0, what)?;
        let block = self.header_value(bytes, 1, what)?;
        let last = self.header_value(bytes, 2, what)?;
        let header_len = blocks
            .checked_add(3)
            .and_then(|b| b.checked_mul(hsize))
            .unwrap_or(usize::MAX);
        if header_len > bytes.len() {
            bail_format!(
                "{what}: its compression header declares {blocks} blocks, more than its {} bytes \
                 of data can describe",
                bytes.len()
            );
        }
        let last = if last == 0 { block } else { last };
        let total = match blocks {
            0 => 0,
            b => (b - 1)
                .checked_mul(block)
                .and_then(|t| t.checked_add(last))
                .unwrap_or(usize::MAX),
        };
        if total != expected || last > block {
            bail_format!(
                "{what}: its compression header declares {blocks} blocks of {block} bytes (the \
                 last {last}), {total} bytes in all, but the array needs {expected}"
            );
        }
        let mut sizes = Vec::with_capacity(blocks);
        let mut compressed_total = 0usize;
        for i in 0..blocks {
            let size = self.header_value(bytes, 3 + i, what)?;
            compressed_total = compressed_total.saturating_add(size);
            sizes.push(size);
        }
        let data = &bytes[header_len..];
        if compressed_total > data.len() {
            bail_format!(
                "{what}: truncated compressed data: {compressed_total} bytes declared, {} present",
                data.len()
            );
        }
        if expected / MAX_DEFLATE_RATIO > compressed_total + blocks {
            bail_format!(
                "{what}: {compressed_total} compressed bytes cannot inflate to the {expected} the \
                 header declares"
            );
        }
        let mut out = vec![0u8; expected];
        let mut from = 0;
        for (i, &size) in sizes.iter().enumerate() {
            let want = if i + 1 == blocks { last } else { block };
            let target = &mut out[i * block..i * block + want];
            let mut z = flate2::Decompress::new(true);
            let status = z.decompress(
                &data[from..from + size],
                target,
                flate2::FlushDecompress::Finish,
            );
            let done =
                matches!(status, Ok(flate2::Status::StreamEnd)) && z.total_out() as usize == want;
            if !done {
                bail_format!(
                    "{what}: zlib block {i} of {blocks} is corrupt or does not inflate to its \
                     {want} bytes ({})",
                    match status {
                        Err(e) => e.to_string(),
                        Ok(_) => format!("{} bytes", z.total_out()),
                    }
                );
            }
            from += size;
        }
        Ok(out)
    }
}

/// Base64 text, whitespace ignored; VTK encodes a header and its data separately, so padding
/// may end a run in the middle: each padded run is decoded on its own.
fn decode_base64(text: &[u8], what: &str) -> Result<Vec<u8>> {
    let clean: Vec<u8> = text
        .iter()
        .copied()
        .filter(|b| !b.is_ascii_whitespace())
        .collect();
    let mut out = Vec::with_capacity(clean.len() / 4 * 3);
    let mut start = 0;
    let engine = base64::engine::general_purpose::STANDARD;
    for (i, group) in clean.chunks(4).enumerate() {
        let end = i * 4 + group.len();
        if group.contains(&b'=') || end == clean.len() {
            engine
                .decode_vec(&clean[start..end], &mut out)
                .map_err(|e| format_failure!("{what}: invalid base64 data: {e}"))?;
            start = end;
        }
    }
    Ok(out)
}

fn ascii(text: &[u8], n: usize, num: Num, what: &str) -> Result<Vec<f32>> {
    if n > text.len() / 2 + 1 {
        bail_format!(
            "{what}: {n} values declared, more than its {} bytes of text can hold",
            text.len()
        );
    }
    let mut out = Vec::with_capacity(n);
    for token in text
        .split(|b| b.is_ascii_whitespace())
        .filter(|t| !t.is_empty())
    {
        if out.len() == n {
            bail_format!("{what}: more than the {n} values declared");
        }
        let token = std::str::from_utf8(token).unwrap_or("\u{fffd}");
        let value = match num {
            Num::F32 | Num::F64 => token.parse::<f64>().ok().map(|v| v as f32),
            _ => token.parse::<i128>().ok().map(|v| v as f32),
        };
        match value {
            Some(v) => out.push(v),
            None => bail_format!(
                "{what}: value {} '{}' is not a number",
                out.len(),
                short(token)
            ),
        }
    }
    if out.len() != n {
        bail_format!("{what}: {} values, but {n} declared", out.len());
    }
    Ok(out)
}
