//! Binary PLY payload, either byte order: the elements before `vertex` are skipped, then the
//! vertices decoded in chunks when their records have a fixed size.

use std::fs::File;
use std::io::{self, BufRead, BufReader, ErrorKind, Read};

use glam::Vec3;

use super::attribute_columns::AttributeColumns;
use super::failure::{Failure, Result};
use super::ply_layout::{Element, Kind, Layout, Scalar};
use super::records::{self, Records};

/// Reads the payload that starts at byte `offset`: the positions, returned, and the
/// attributes.
pub(super) fn read(
    reader: &mut BufReader<File>,
    layout: &Layout,
    attributes: &mut AttributeColumns,
    big_endian: bool,
    mut offset: u64,
    file_len: u64,
) -> Result<Vec<Vec3>> {
    for element in &layout.before {
        offset = skip(reader, element, big_endian, offset, file_len)?;
    }
    let vertex = &layout.vertex;
    let Some(stride) = vertex.fixed_stride() else {
        return read_varying(reader, layout, attributes, big_endian, offset, file_len);
    };
    let records = Records {
        count: vertex.count,
        stride,
        start: offset,
        file_len,
        what: "vertex",
    };
    let [(ax, sx), (ay, sy), (az, sz)] = layout
        .xyz
        .map(|(i, scalar)| (vertex.scalar_offset(i), scalar));
    // Index, offset in the record and type of each attribute's property.
    let columns: Vec<(usize, usize, Scalar)> = vertex
        .props
        .iter()
        .enumerate()
        .filter_map(|(i, p)| match p.kind {
            Kind::Scalar(scalar) if attributes.reads(i) => {
                Some((i, vertex.scalar_offset(i), scalar))
            }
            _ => None,
        })
        .collect();
    // The count is checked against the file's size before anything is allocated for it.
    records.check()?;
    let end = offset + records.count as u64 * stride as u64;
    if layout.vertex_is_last && file_len - end >= stride as u64 {
        // A whole record or more after the last element: the count is wrong. (A few stray
        // bytes, such as a final newline, are tolerated.)
        bail_format!(
            "the header declares {} vertices of {stride} bytes, ending at byte offset {end},              but the file goes on to byte offset {file_len}: the vertex count is too small",
            records.count
        );
    }
    attributes.reserve(records.count);
    let decode = |record: &[u8], p: &mut Vec3| {
        p.x = sx.to_f32(record.get(ax..)?, big_endian)?;
        p.y = sy.to_f32(record.get(ay..)?, big_endian)?;
        p.z = sz.to_f32(record.get(az..)?, big_endian)?;
        Some(())
    };
    // The attributes are decoded a column at a time, after the positions of each chunk, which
    // leaves the positions' loop as tight as without them.
    records::read(reader, &records, decode, |first, chunk| {
        attributes.resize(first + chunk.len() / stride);
        for &(i, at, scalar) in &columns {
            let values = chunk.chunks_exact(stride);
            let values = values.map(|record| scalar.to_f32(record.get(at..)?, big_endian));
            attributes.fill(i, first, values)?;
        }
        Some(())
    })
}

/// Skips the records of a binary element that starts at byte `offset`; returns where it ends.
fn skip(
    reader: &mut BufReader<File>,
    element: &Element,
    big_endian: bool,
    offset: u64,
    file_len: u64,
) -> Result<u64> {
    if let Some(stride) = element.fixed_stride() {
        let remaining = file_len.saturating_sub(offset);
        let Some(bytes) = (element.count as u64)
            .checked_mul(stride as u64)
            .filter(|&bytes| bytes <= remaining)
        else {
            bail_format!(
                "truncated binary data: element '{}' declares {} records of {stride} bytes from \
                 byte offset {offset}, but the file ends at byte offset {file_len}",
                element.name,
                element.count
            );
        };
        // `bytes` is at most the file's length, which fits in an i64.
        let bytes_i64 = i64::try_from(bytes).unwrap_or(i64::MAX);
        reader
            .seek_relative(bytes_i64)
            .map_err(|e| Failure::io(format_args!("read error at byte offset {offset}"), e))?;
        return Ok(offset + bytes);
    }
    (0..element.count).try_fold(offset, |offset, index| {
        walk_record(
            reader,
            element,
            index,
            big_endian,
            offset,
            file_len,
            |_, _, _| {},
        )
    })
}

/// Reads vertex records that contain list properties, one property at a time.
fn read_varying(
    reader: &mut BufReader<File>,
    layout: &Layout,
    attributes: &mut AttributeColumns,
    big_endian: bool,
    mut offset: u64,
    file_len: u64,
) -> Result<Vec<Vec3>> {
    let (vertex, xyz) = (&layout.vertex, layout.xyz_indices());
    // Every record holds at least its scalars and list lengths, which bounds the allocation.
    let min_record: usize = vertex.props.iter().map(|p| p.kind.head_size()).sum();
    let fit = file_len.saturating_sub(offset) / min_record.max(1) as u64;
    let capacity = vertex.count.min(usize::try_from(fit).unwrap_or(usize::MAX));
    let mut out = Vec::with_capacity(capacity);
    attributes.reserve(capacity);
    for index in 0..vertex.count {
        let start = offset;
        let mut coordinates = [None; 3];
        let mut decoded = true;
        attributes.push();
        offset = walk_record(
            reader,
            vertex,
            index,
            big_endian,
            offset,
            file_len,
            |i, s, bytes| {
                if let Some(c) = xyz.iter().position(|&j| j == i) {
                    coordinates[c] = s.to_f32(bytes, big_endian);
                } else if attributes.reads(i) {
                    match s.to_f32(bytes, big_endian) {
                        Some(value) => attributes.set_last(i, value),
                        None => decoded = false,
                    }
                }
            },
        )?;
        let ([Some(x), Some(y), Some(z)], true) = (coordinates, decoded) else {
            bail_format!("cannot decode vertex {index} at byte offset {start}");
        };
        out.push(super::failure::finite(Vec3::new(x, y, z), || {
            format!("vertex {index} (byte offset {start})")
        })?);
    }
    Ok(out)
}

/// Reads record `index` of a binary `element` from byte `offset`, passing each scalar property's
/// index, type and bytes to `visit`; returns the offset after the record.
fn walk_record(
    reader: &mut impl BufRead,
    element: &Element,
    index: usize,
    big_endian: bool,
    mut offset: u64,
    file_len: u64,
    mut visit: impl FnMut(usize, Scalar, &[u8]),
) -> Result<u64> {
    let truncated = || {
        format_failure!(
            "truncated binary data: the file ends at byte offset {file_len}, inside {} record \
             {index} of {}",
            element.name,
            element.count
        )
    };
    let mut buf = [0; 8];
    for (i, prop) in element.props.iter().enumerate() {
        match prop.kind {
            Kind::Scalar(scalar) => {
                let bytes = &mut buf[..scalar.size()];
                if !read_field(reader, bytes, offset)? {
                    return Err(truncated());
                }
                visit(i, scalar, bytes);
                offset += scalar.size() as u64;
            }
            Kind::List { len, item } => {
                let bytes = &mut buf[..len.size()];
                if !read_field(reader, bytes, offset)? {
                    return Err(truncated());
                }
                let n = len.to_len(bytes, big_endian).ok_or_else(|| {
                    format_failure!(
                        "negative list length for property '{}' of {} record {index} at byte offset {offset}",
                        super::failure::short(&prop.name),
                        element.name
                    )
                })?;
                offset += len.size() as u64;
                let skip = n.checked_mul(item.size() as u64).ok_or_else(truncated)?;
                let skipped =
                    io::copy(&mut (&mut *reader).take(skip), &mut io::sink()).map_err(|e| {
                        Failure::io(format_args!("read error at byte offset {offset}"), e)
                    })?;
                if skipped < skip {
                    return Err(truncated());
                }
                offset += skip;
            }
        }
    }
    Ok(offset)
}

/// Fills `buf` from the reader; `false` if the file ends first.
fn read_field(reader: &mut impl Read, buf: &mut [u8], offset: u64) -> Result<bool> {
    match reader.read_exact(buf) {
        Ok(()) => Ok(true),
        Err(e) if e.kind() == ErrorKind::UnexpectedEof => Ok(false),
        Err(e) => Err(Failure::io(
            format_args!("read error at byte offset {offset}"),
            e,
        )),
    }
}
