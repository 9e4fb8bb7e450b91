//! The layout a PLY header declares: its elements, their properties and scalar types, and
//! where the vertex coordinates are; what `ply_binary_read` and `ply_ascii_read` read the
//! payload by.

use ply_rs_bw::ply::{ElementDef, Header, PropertyType, ScalarType};

use super::failure::Result;

/// What the payload readers need from the header.
pub(in crate::io) struct Layout {
    /// The elements before `vertex`, to skip. Those after it are never read, so neither is
    /// their layout checked.
    pub before: Vec<Element>,
    pub vertex: Element,
    /// Whether `vertex` is the file's last element, so that nothing may follow its records.
    pub vertex_is_last: bool,
    /// Index and type of each of the vertex properties `x`, `y`, `z`.
    pub xyz: [(usize, Scalar); 3],
}

impl Layout {
    pub fn new(header: &Header) -> Result<Self> {
        let Some((vertex_index, _, vertex)) = header.elements.get_full("vertex") else {
            let names: Vec<&str> = header.elements.keys().map(String::as_str).collect();
            bail_format!(
                "the PLY header has no 'vertex' element (its elements: {})",
                super::failure::listed(names.iter().copied())
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
            vertex_is_last: vertex_index + 1 == header.elements.len(),
            vertex,
            xyz,
        })
    }

    /// Indices of the vertex properties `x`, `y`, `z`.
    pub fn xyz_indices(&self) -> [usize; 3] {
        self.xyz.map(|(i, _)| i)
    }
}

#[derive(Clone, Copy, Debug)]
pub(in crate::io) enum Scalar {
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
pub(in crate::io) enum Kind {
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

pub(in crate::io) struct Property {
    pub name: String,
    pub kind: Kind,
}

/// An element's layout, as needed to read or skip its records.
pub(in crate::io) struct Element {
    pub name: String,
    pub count: usize,
    pub props: Vec<Property>,
}

impl Element {
    pub(in crate::io) fn new(def: &ElementDef) -> Result<Self> {
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
                                super::failure::short(&p.name),
                                super::failure::short(&def.name)
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
            // For messages only (a header's names may be a megabyte long).
            name: super::failure::short(&def.name),
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
                super::failure::listed(names.iter().copied())
            );
        };
        let Kind::Scalar(scalar) = prop.kind else {
            bail_format!("the 'vertex' property '{name}' is a list, not a number");
        };
        *slot = (index, scalar);
    }
    Ok(xyz)
}
