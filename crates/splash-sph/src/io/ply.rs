//! PLY particle input.
//!
//! ply_rs_bw parses the header; the payload is decoded here, because its payload reader builds a
//! map per element (far too slow for millions of particles) and preallocates from the untrusted
//! header count. Only the elements up to `vertex` are read: those before it are skipped, those
//! after it ignored. This module reads the header and the layout it declares; `ply_binary` and
//! `ply_ascii` read the payload.

use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{DefaultElement, ElementDef, Encoding, Header, PropertyType, ScalarType};

use super::Particles;
use super::attribute_columns::AttributeColumns;
use super::failure::{Failure, Result};
use super::lines::Lines;
use super::{ply_ascii, ply_binary};

/// Headers are a few hundred bytes; the cap keeps a non-PLY file from being read whole.
const MAX_HEADER_BYTES: u64 = 1 << 20;

/// Reads the `vertex` element's coordinates and every other scalar property of it as an
/// attribute (list properties are skipped).
pub(super) fn read(path: &Path) -> Result<Particles> {
    let (file, file_len) = super::open_input(path)?;
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
            ply_ascii::read(lines, &layout, columns, file_len.saturating_sub(header_len))
        }
        Encoding::BinaryLittleEndian => {
            ply_binary::read(&mut reader, &layout, columns, false, header_len, file_len)
        }
        Encoding::BinaryBigEndian => {
            ply_binary::read(&mut reader, &layout, columns, true, header_len, file_len)
        }
    }?;
    Ok(Particles {
        positions,
        attributes: attributes.into_map(),
    })
}

/// What the payload readers need from the header.
pub(super) struct Layout {
    /// The elements before `vertex`, to skip. Those after it are never read, so neither is
    /// their layout checked.
    pub before: Vec<Element>,
    pub vertex: Element,
    /// Index and type of each of the vertex properties `x`, `y`, `z`.
    pub xyz: [(usize, Scalar); 3],
}

impl Layout {
    fn new(header: &Header) -> Result<Self> {
        let Some((vertex_index, _, vertex)) = header.elements.get_full("vertex") else {
            let names: Vec<&str> = header.elements.keys().map(String::as_str).collect();
            bail_format!(
                "the PLY header has no 'vertex' element (its elements: {})",
                names.join(", ")
            );
        };
        let vertex = Element::new(vertex)?;
        let before = header
            .elements
            .values()
            .take(vertex_index)
            .map(Element::new)
            .collect::<Result<_>>()?;
        let xyz = coordinate_properties(&vertex)?;
        Ok(Self {
            before,
            vertex,
            xyz,
        })
    }

    /// Indices of the vertex properties `x`, `y`, `z`.
    pub fn xyz_indices(&self) -> [usize; 3] {
        self.xyz.map(|(i, _)| i)
    }
}

/// Reads the header up to `end_header`, returning it with its length in bytes and lines.
fn read_header(reader: &mut BufReader<File>) -> Result<(Header, u64, usize)> {
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
    let header = Parser::<DefaultElement>::new()
        .read_header(&mut Reader::new(bytes.as_slice()))
        .map_err(|e| {
            // The parser's message spans several indented lines and ends with a dump of the
            // grammar's expectations: keep the line number and text.
            let message = e.to_string();
            let message = message.split("\n\tError:").next().unwrap_or_default();
            let words: Vec<&str> = message.split_whitespace().collect();
            format_failure!("malformed PLY header: {}", words.join(" "))
        })?;
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

#[derive(Clone, Copy, Debug)]
pub(super) enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

/// Decodes a `$t` from the start of `$bytes`, returning `None` from the function if too short.
macro_rules! decode {
    ($t:ty, $bytes:expr, $big_endian:expr) => {{
        let raw = $bytes.get(..size_of::<$t>())?.try_into().ok()?;
        if $big_endian {
            <$t>::from_be_bytes(raw)
        } else {
            <$t>::from_le_bytes(raw)
        }
    }};
}

impl Scalar {
    fn new(scalar: &ScalarType) -> Self {
        match scalar {
            ScalarType::Char => Self::I8,
            ScalarType::UChar => Self::U8,
            ScalarType::Short => Self::I16,
            ScalarType::UShort => Self::U16,
            ScalarType::Int => Self::I32,
            ScalarType::UInt => Self::U32,
            ScalarType::Float => Self::F32,
            ScalarType::Double => Self::F64,
        }
    }

    pub fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Self::F32 | Self::F64)
    }

    pub fn to_f32(self, bytes: &[u8], big_endian: bool) -> Option<f32> {
        Some(match self {
            Self::I8 => f32::from(decode!(i8, bytes, big_endian)),
            Self::U8 => f32::from(decode!(u8, bytes, big_endian)),
            Self::I16 => f32::from(decode!(i16, bytes, big_endian)),
            Self::U16 => f32::from(decode!(u16, bytes, big_endian)),
            Self::I32 => decode!(i32, bytes, big_endian) as f32,
            Self::U32 => decode!(u32, bytes, big_endian) as f32,
            Self::F32 => decode!(f32, bytes, big_endian),
            Self::F64 => decode!(f64, bytes, big_endian) as f32,
        })
    }

    /// A list length: `None` if negative (or not an integer type, which the header check rules
    /// out).
    pub fn to_len(self, bytes: &[u8], big_endian: bool) -> Option<u64> {
        match self {
            Self::I8 => u64::try_from(decode!(i8, bytes, big_endian)).ok(),
            Self::U8 => Some(u64::from(decode!(u8, bytes, big_endian))),
            Self::I16 => u64::try_from(decode!(i16, bytes, big_endian)).ok(),
            Self::U16 => Some(u64::from(decode!(u16, bytes, big_endian))),
            Self::I32 => u64::try_from(decode!(i32, bytes, big_endian)).ok(),
            Self::U32 => Some(u64::from(decode!(u32, bytes, big_endian))),
            Self::F32 | Self::F64 => None,
        }
    }
}

#[derive(Clone, Copy, Debug)]
pub(super) enum Kind {
    Scalar(Scalar),
    List { len: Scalar, item: Scalar },
}

impl Kind {
    /// Bytes before any list items: the whole of a scalar, the length of a list.
    pub fn head_size(self) -> usize {
        match self {
            Self::Scalar(s) | Self::List { len: s, .. } => s.size(),
        }
    }
}

pub(super) struct Property {
    pub name: String,
    pub kind: Kind,
}

/// An element's layout, as needed to read or skip its records.
pub(super) struct Element {
    pub name: String,
    pub count: usize,
    pub props: Vec<Property>,
}

impl Element {
    fn new(def: &ElementDef) -> Result<Self> {
        let props = def
            .properties
            .values()
            .map(|p| {
                let kind = match &p.data_type {
                    PropertyType::Scalar(s) => Kind::Scalar(Scalar::new(s)),
                    PropertyType::List(len, item) => {
                        let len = Scalar::new(len);
                        if !len.is_integer() {
                            bail_format!(
                                "malformed PLY header: list property '{}' of element '{}' has a \
                                 non-integer length type",
                                p.name,
                                def.name
                            );
                        }
                        Kind::List {
                            len,
                            item: Scalar::new(item),
                        }
                    }
                };
                Ok(Property {
                    name: p.name.clone(),
                    kind,
                })
            })
            .collect::<Result<_>>()?;
        Ok(Self {
            name: def.name.clone(),
            count: def.count,
            props,
        })
    }

    /// Record size in bytes, if there are no list properties.
    pub fn fixed_stride(&self) -> Option<usize> {
        self.props
            .iter()
            .map(|p| match p.kind {
                Kind::Scalar(s) => Some(s.size()),
                Kind::List { .. } => None,
            })
            .sum()
    }

    /// Offset of property `index` within a fixed-stride record.
    pub fn scalar_offset(&self, index: usize) -> usize {
        self.props
            .iter()
            .take(index)
            .map(|p| p.kind.head_size())
            .sum()
    }
}

/// Index and type of each of the vertex properties `x`, `y`, `z`.
fn coordinate_properties(vertex: &Element) -> Result<[(usize, Scalar); 3]> {
    let mut xyz = [(0, Scalar::F32); 3];
    for (slot, name) in xyz.iter_mut().zip(["x", "y", "z"]) {
        let Some((index, prop)) = vertex
            .props
            .iter()
            .enumerate()
            .find(|(_, p)| p.name == name)
        else {
            let names: Vec<&str> = vertex.props.iter().map(|p| p.name.as_str()).collect();
            bail_format!(
                "the 'vertex' element has no property '{name}' (its properties: {})",
                names.join(", ")
            );
        };
        let Kind::Scalar(scalar) = prop.kind else {
            bail_format!("the 'vertex' property '{name}' is a list, not a number");
        };
        *slot = (index, scalar);
    }
    Ok(xyz)
}
