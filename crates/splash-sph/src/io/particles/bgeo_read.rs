//! Classic BGEO input (`.bgeo`, `.bgeo.gz`, version 5, as partio, SPlisHSPlasH and splashsurf
//! write it): magic `BgeoV`, version, eight big-endian `i32` counts (points, primitives,
//! point groups, primitive groups, point/vertex/primitive/detail attributes), the point
//! attribute definitions (name, size, type, defaults), then per point `x y z w` and the
//! attributes' values, all big-endian 32-bit. A gzip-compressed file (splashsurf writes them
//! whatever the extension) is recognised by its magic bytes. Float and vector attributes are
//! read as they are, int attributes converted to `f32`; indexed-string attributes (type 4) are
//! read past and not returned. Houdini's newer binary-JSON `.bgeo` and Blosc `.bgeo.sc` are
//! refused with a clear message.

use std::io::Read;
use std::path::Path;

use super::failure::{Failure, Result};
use super::point_arrays::{self, Num, PointArray};
use crate::data::Particles;

/// A decompressed `.bgeo.gz` may be at most this large (and, before that, what its header
/// declares): the points of a 1 G-particle frame of position and a few attributes.
const MAX_INFLATED: u64 = 64 << 30;

const HEADER_BYTES: usize = 5 + 4 + 8 * 4;

pub(super) fn read(path: &Path) -> Result<Particles> {
    let name = path
        .file_name()
        .and_then(|n| n.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    if name.ends_with(".sc") {
        bail_format!(
            "Blosc-compressed BGEO (.bgeo.sc, Houdini's newer format) is not supported yet: \
             save the frame as classic .bgeo or .bgeo.gz (version 5), or as .vtk/.vtu"
        );
    }
    let data = point_arrays::read_all(path)?;
    if data.starts_with(&[0x1f, 0x8b]) {
        let inflated = inflate(&data)?;
        parse(&inflated)
    } else {
        parse(&data)
    }
}

/// Decompresses a gzip file, at most as much as its header declares (read from the first
/// decompressed bytes) and [`MAX_INFLATED`].
fn inflate(data: &[u8]) -> Result<Vec<u8>> {
    let mut decoder = flate2::read::MultiGzDecoder::new(data);
    let mut head = Vec::with_capacity(HEADER_BYTES);
    (&mut decoder)
        .take(HEADER_BYTES as u64)
        .read_to_end(&mut head)
        .map_err(|e| format_failure!("gzip data is corrupt: {e}"))?;
    let points = if head.len() == HEADER_BYTES {
        be_u32(&head, 9) as u64
    } else {
        0
    };
    let attributes = if head.len() == HEADER_BYTES {
        be_u32(&head, 25) as u64
    } else {
        0
    };
    // Each attribute definition is at most 2 + 65535 + 2 + 4 + 4 × 65535 bytes, each point at
    // most 16 + 4 × 65535 × attributes bytes: a loose bound, tightened by MAX_INFLATED.
    let per_point = 16 + attributes.saturating_mul(4 * 65535);
    let limit = (HEADER_BYTES as u64 + 64)
        .saturating_add(attributes.saturating_mul(2 + 65535 + 6 + 4 * 65535))
        .saturating_add(points.saturating_mul(per_point))
        .min(MAX_INFLATED)
        // Deflate inflates at most about 1032:1: a real file never meets this bound.
        .min(
            (data.len() as u64)
                .saturating_mul(1032)
                .saturating_add(4096),
        );
    let mut out = head;
    (&mut decoder)
        .take(limit + 1)
        .read_to_end(&mut out)
        .map_err(|e| format_failure!("gzip data is corrupt: {e}"))?;
    if out.len() as u64 > limit + HEADER_BYTES as u64 {
        bail_format!(
            "the gzip data inflates to more than the {limit} bytes its BGEO header allows"
        );
    }
    Ok(out)
}

fn be_u32(b: &[u8], at: usize) -> u32 {
    u32::from_be_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

struct Cursor<'a> {
    data: &'a [u8],
    pos: usize,
}

impl<'a> Cursor<'a> {
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8]> {
        if n > self.data.len() - self.pos {
            bail_format!(
                "truncated BGEO data: {what} needs {n} bytes at byte offset {}, but the data \
                 ends at byte offset {}",
                self.pos,
                self.data.len()
            );
        }
        let out = &self.data[self.pos..self.pos + n];
        self.pos += n;
        Ok(out)
    }

    fn u16(&mut self, what: &str) -> Result<u16> {
        let b = self.take(2, what)?;
        Ok(u16::from_be_bytes([b[0], b[1]]))
    }

    fn i32(&mut self, what: &str) -> Result<i32> {
        let b = self.take(4, what)?;
        Ok(i32::from_be_bytes([b[0], b[1], b[2], b[3]]))
    }

    fn count(&mut self, what: &str) -> Result<usize> {
        let at = self.pos;
        let n = self.i32(what)?;
        usize::try_from(n)
            .map_err(|_| format_failure!("the {what} at byte offset {at} is negative: {n}"))
    }
}

/// Offsets are into the decompressed data for a `.bgeo.gz`.
fn parse(data: &[u8]) -> Result<Particles> {
    if data.starts_with(b"\x7fNSJb") || data.first() == Some(&b'[') || data.first() == Some(&b'{') {
        bail_format!(
            "this is Houdini's newer JSON BGEO, which is not supported yet: save the frame as \
             classic BGEO (version 5; partio, SPlisHSPlasH and splashsurf write it) or as .vtk/.vtu"
        );
    }
    if !data.starts_with(b"BgeoV") {
        bail_format!(
            "not a BGEO file: it does not start with the magic bytes 'BgeoV' (nor with gzip's)"
        );
    }
    let mut c = Cursor { data, pos: 5 };
    let version = c.i32("the version")?;
    if version != 5 {
        bail_format!("unsupported BGEO version {version} at byte offset 5: splash reads version 5");
    }
    let points = c.count("point count")?;
    let _primitives = c.count("primitive count")?;
    let _point_groups = c.count("point group count")?;
    let _primitive_groups = c.count("primitive group count")?;
    let attribute_count = c.count("point attribute count")?;
    let _vertex_attributes = c.count("vertex attribute count")?;
    let _primitive_attributes = c.count("primitive attribute count")?;
    let _detail_attributes = c.count("detail attribute count")?;

    struct Definition {
        name: String,
        size: usize,
        /// Returned (float, int, vector) or read past (indexed string).
        keep: Option<Num>,
    }
    let mut definitions = Vec::new();
    let mut floats_per_point = 4usize;
    for index in 0..attribute_count {
        let at = c.pos;
        let len = c.u16("an attribute name's length")? as usize;
        let name = String::from_utf8_lossy(c.take(len, "an attribute name")?).into_owned();
        let size = c.u16("an attribute's size")? as usize;
        let ty = c.i32("an attribute's type")?;
        let keep = match ty {
            0 | 5 => Some(Num::F32),
            1 => Some(Num::I32),
            4 => None,
            other => bail_format!(
                "point attribute {index} ('{}', byte offset {at}) has type {other}; splash reads \
                 float (0), int (1), indexed string (4) and vector (5) attributes",
                super::failure::short(&name)
            ),
        };
        if keep.is_some() {
            c.take(4 * size, "an attribute's default value")?;
        } else {
            let strings = c.count("an indexed string attribute's string count")?;
            for _ in 0..strings {
                let len = c.u16("an indexed string's length")? as usize;
                c.take(len, "an indexed string")?;
            }
        }
        floats_per_point += size;
        definitions.push(Definition { name, size, keep });
    }
    let stride = floats_per_point * 4;
    let start = c.pos;
    let needed = points.saturating_mul(stride);
    if needed > data.len() - start {
        bail_format!(
            "truncated BGEO data: {points} points of {stride} bytes from byte offset {start} need \
             {needed} bytes, but the data ends at byte offset {}, after {} complete points",
            data.len(),
            (data.len() - start) / stride
        );
    }
    let records = &data[start..start + needed];
    let mut positions = Vec::with_capacity(points * 3);
    for record in records.chunks_exact(stride) {
        Num::F32.decode_into(&record[..12], true, &mut positions);
    }
    let mut arrays = Vec::new();
    let mut offset = 16;
    for d in definitions {
        if let Some(num) = d.keep {
            let mut values = Vec::with_capacity(points * d.size);
            for record in records.chunks_exact(stride) {
                num.decode_into(&record[offset..offset + 4 * d.size], true, &mut values);
            }
            arrays.push(PointArray {
                name: d.name,
                width: d.size,
                values,
            });
        }
        offset += 4 * d.size;
    }
    point_arrays::particles(&positions, arrays).map_err(|e| match e {
        Failure::Format(m) => {
            Failure::Format(format!("{m} (BGEO point records from byte offset {start})"))
        }
        other => other,
    })
}
