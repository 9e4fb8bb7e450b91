//! Raw particle input: little-endian `f32` `x y z` triples, no header.

use std::collections::BTreeMap;
use std::path::Path;

use glam::Vec3;

use super::failure::Result;
use super::records::{self, Records};
use crate::data::Particles;

const RECORD_BYTES: usize = 12;

pub(super) fn read(path: &Path) -> Result<Particles> {
    let (mut file, file_len) = super::failure::open_input(path)?;
    let remainder = file_len % RECORD_BYTES as u64;
    if remainder != 0 {
        bail_format!(
            "raw particle data is a sequence of {RECORD_BYTES}-byte records (x, y, z as \
             little-endian f32), but the file is {file_len} bytes long, not a multiple of \
             {RECORD_BYTES} (remainder {remainder})"
        );
    }
    let records = Records {
        // Beyond usize, the count would be refused as more records than the file holds.
        count: usize::try_from(file_len / RECORD_BYTES as u64).unwrap_or(usize::MAX),
        stride: RECORD_BYTES,
        start: 0,
        file_len,
        what: "particle",
    };
    let decode = |r: &[u8], p: &mut Vec3| {
        p.x = f32_le(r, 0)?;
        p.y = f32_le(r, 4)?;
        p.z = f32_le(r, 8)?;
        Some(())
    };
    let positions = records::read(&mut file, &records, decode, |_, _| Some(()))?;
    Ok(Particles {
        positions,
        attributes: BTreeMap::new(),
    })
}

fn f32_le(record: &[u8], at: usize) -> Option<f32> {
    Some(f32::from_le_bytes(record.get(at..at + 4)?.try_into().ok()?))
}
