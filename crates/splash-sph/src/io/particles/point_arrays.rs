//! What the VTK and BGEO readers share: numeric types of binary arrays, and named per-point
//! arrays of any width turned into [`Particles`].

use std::collections::BTreeMap;

use glam::Vec3;

use super::failure::Result;
use crate::data::{Attribute, Particles};

/// A numeric type of a binary or text array.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Num {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
}

impl Num {
    pub fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::I64 | Self::U64 | Self::F64 => 8,
        }
    }

    /// Appends the values of `bytes` (whole values only: `bytes.len()` a multiple of the size)
    /// to `out`, converted to `f32`.
    pub fn decode_into(self, bytes: &[u8], big_endian: bool, out: &mut Vec<f32>) {
        macro_rules! each {
            ($t:ty) => {{
                const N: usize = std::mem::size_of::<$t>();
                out.extend(bytes.chunks_exact(N).map(|c| {
                    let b: [u8; N] = c.try_into().unwrap_or([0; N]);
                    (if big_endian {
                        <$t>::from_be_bytes(b)
                    } else {
                        <$t>::from_le_bytes(b)
                    }) as f32
                }))
            }};
        }
        match self {
            Self::I8 => each!(i8),
            Self::U8 => each!(u8),
            Self::I16 => each!(i16),
            Self::U16 => each!(u16),
            Self::I32 => each!(i32),
            Self::U32 => each!(u32),
            Self::I64 => each!(i64),
            Self::U64 => each!(u64),
            Self::F32 => each!(f32),
            Self::F64 => each!(f64),
        }
    }
}

impl Num {
    /// One value (`bytes` its size) as a vertex or cell number: `None` if negative or not an
    /// integer type.
    pub fn to_index(self, bytes: &[u8], big_endian: bool) -> Option<u64> {
        macro_rules! one {
            ($t:ty) => {{
                let b = bytes.try_into().ok()?;
                let v = if big_endian {
                    <$t>::from_be_bytes(b)
                } else {
                    <$t>::from_le_bytes(b)
                };
                u64::try_from(v).ok()
            }};
        }
        match self {
            Self::I8 => one!(i8),
            Self::U8 => one!(u8),
            Self::I16 => one!(i16),
            Self::U16 => one!(u16),
            Self::I32 => one!(i32),
            Self::U32 => one!(u32),
            Self::I64 => one!(i64),
            Self::U64 => one!(u64),
            Self::F32 | Self::F64 => None,
        }
    }
}

/// One named per-point array of `width` components per point, flattened.
pub(super) struct PointArray {
    pub name: String,
    pub width: usize,
    pub values: Vec<f32>,
}

/// Particles from flat `x y z` positions and per-point arrays (each of `width × points`
/// values): width 1 is a scalar attribute, width 3 a vector, any other width one scalar per
/// component, `{name}_0`, `{name}_1`, …. Of two arrays of one name the first is kept.
/// Positions must be finite; `what` names a point in messages ("point").
pub(super) fn particles(positions: &[f32], arrays: Vec<PointArray>) -> Result<Particles> {
    let mut points = Vec::with_capacity(positions.len() / 3);
    for (i, p) in positions.chunks_exact(3).enumerate() {
        let p = Vec3::new(p[0], p[1], p[2]);
        points.push(super::failure::finite(p, || format!("point {i}"))?);
    }
    let mut attributes = BTreeMap::new();
    for array in arrays {
        debug_assert_eq!(array.values.len(), array.width * points.len());
        match array.width {
            1 => {
                attributes
                    .entry(array.name)
                    .or_insert(Attribute::Scalar(array.values));
            }
            3 => {
                let vectors = array
                    .values
                    .chunks_exact(3)
                    .map(|v| Vec3::new(v[0], v[1], v[2]))
                    .collect();
                attributes
                    .entry(array.name)
                    .or_insert(Attribute::Vector(vectors));
            }
            width => {
                for c in 0..width {
                    let column = array.values.iter().skip(c).step_by(width).copied();
                    attributes
                        .entry(format!("{}_{c}", array.name))
                        .or_insert_with(|| Attribute::Scalar(column.collect()));
                }
            }
        }
    }
    Ok(Particles {
        positions: points,
        attributes,
    })
}

/// Reads the whole file (bounded by its size, which the caller checked by opening it).
pub(in crate::io) fn read_all(path: &std::path::Path) -> Result<Vec<u8>> {
    use std::io::Read;
    let (mut file, len) = super::failure::open_input(path)?;
    let mut data = Vec::with_capacity(usize::try_from(len).unwrap_or(0).min(1 << 30));
    file.read_to_end(&mut data)
        .map_err(|e| super::failure::Failure::io("read error", e))?;
    Ok(data)
}
