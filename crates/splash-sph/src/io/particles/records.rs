//! Fixed-size binary records, read in chunks: shared by binary PLY and raw input.

use std::io::{ErrorKind, Read};

use glam::Vec3;

use super::failure::{Failure, Result};

/// Bytes read per chunk: large enough to amortise the read calls, small enough that the buffer
/// is negligible next to the output (the whole file is never held in memory).
const CHUNK_BYTES: usize = 1 << 20;

/// Where the records are: `count` records of `stride` bytes from absolute byte `start` of a file
/// of `file_len` bytes; `what` names one record in messages ("vertex", "particle").
pub(super) struct Records<'a> {
    pub count: usize,
    pub stride: usize,
    pub start: u64,
    pub file_len: u64,
    pub what: &'a str,
}

impl Records<'_> {
    /// Fails if the file is too short for `count` records (`count` comes from an untrusted
    /// header): allocations for them are then bounded by the file's size.
    pub fn check(&self) -> Result<()> {
        let &Records {
            count,
            stride,
            start,
            file_len,
            what,
        } = self;
        let complete = file_len.saturating_sub(start) / stride as u64;
        if count as u64 > complete {
            bail_format!(
                "truncated binary data: expected {count} {what} records of {stride} bytes from \
                 byte offset {start}, but the file ends at byte offset {file_len}, after \
                 {complete} complete {what} records"
            );
        }
        Ok(())
    }
}

/// Reads the records, decoding each into a point with `decode` (`None` if it cannot, which
/// well-formed layouts rule out), and rejects non-finite coordinates; then passes each chunk
/// of records, with the index of its first, to `rest`, for whatever else they hold. Fails
/// before reading or allocating anything if the [check](Records::check) fails.
pub(super) fn read(
    reader: &mut impl Read,
    records: &Records,
    mut decode: impl FnMut(&[u8], &mut Vec3) -> Option<()>,
    mut rest: impl FnMut(usize, &[u8]) -> Option<()>,
) -> Result<Vec<Vec3>> {
    records.check()?;
    let &Records {
        count,
        stride,
        start,
        what,
        ..
    } = records;
    let mut out = Vec::with_capacity(count);
    let per_chunk = (CHUNK_BYTES / stride).max(1);
    let mut buf = vec![0; per_chunk.min(count) * stride];
    while out.len() < count {
        let chunk = &mut buf[..per_chunk.min(count - out.len()) * stride];
        let got = fill(reader, chunk)?;
        if got < chunk.len() {
            // Only if the file shrank after its size was checked.
            let end = start + (out.len() * stride + got) as u64;
            bail_format!(
                "truncated binary data: the file ends at byte offset {end}, inside {what} {} of {count}",
                out.len() + got / stride
            );
        }
        // Decoding writes the coordinates in place: returning a Vec3 per record and pushing it
        // made the compiler spill and reload it through the stack, several times slower.
        let first = out.len();
        out.resize(first + chunk.len() / stride, Vec3::ZERO);
        for (i, (record, p)) in chunk
            .chunks_exact(stride)
            .zip(&mut out[first..])
            .enumerate()
        {
            let index = first + i;
            let offset = start + (index * stride) as u64;
            if decode(record, p).is_none() {
                bail_format!("cannot decode {what} {index} at byte offset {offset}");
            }
            if !p.is_finite() {
                return Err(super::failure::non_finite(
                    *p,
                    &format!("{what} {index} (byte offset {offset})"),
                ));
            }
        }
        if rest(first, chunk).is_none() {
            let offset = start + (first * stride) as u64;
            bail_format!("cannot decode the {what} records from byte offset {offset}");
        }
    }
    Ok(out)
}

/// Reads until `buf` is full or the input ends; returns the number of bytes read.
fn fill(reader: &mut impl Read, buf: &mut [u8]) -> Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match reader.read(&mut buf[got..]) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(e) => return Err(Failure::io("read error", e)),
        }
    }
    Ok(got)
}
