//! `.xyz` input: splashsurf's raw little-endian `f32` `x y z` triples, or, when the file's
//! start is text, a text table of numbers (read as CSV/whitespace text, see
//! [`super::read_particles`]).

use std::io::Read;
use std::path::Path;

use super::failure::{Failure, Result};
use crate::data::Particles;

/// Bytes looked at to tell text from binary.
const SNIFF_BYTES: usize = 4096;

pub(super) fn read(path: &Path) -> Result<Particles> {
    if is_text(path)? {
        super::csv_read::read(path)
    } else {
        super::raw_read::read(path)
    }
}

/// Whether the file starts with text: only printable ASCII and whitespace, beginning with
/// something a table of numbers can begin with. An empty file is raw (no particles).
fn is_text(path: &Path) -> Result<bool> {
    let (file, _) = super::failure::open_input(path)?;
    let mut head = Vec::with_capacity(SNIFF_BYTES);
    file.take(SNIFF_BYTES as u64)
        .read_to_end(&mut head)
        .map_err(|e| Failure::io("read error", e))?;
    let printable = head
        .iter()
        .all(|&b| b.is_ascii_graphic() || matches!(b, b' ' | b'\t' | b'\r' | b'\n'));
    let starts_like_text = head
        .iter()
        .find(|b| !b.is_ascii_whitespace())
        .is_some_and(|&b| {
            b.is_ascii_alphanumeric() || matches!(b, b'-' | b'+' | b'.' | b'#' | b'"')
        });
    Ok(!head.is_empty() && printable && starts_like_text)
}
