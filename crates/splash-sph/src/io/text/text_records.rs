//! Text payloads formatted on all threads: the records (lines) are cut into chunks, a wave of
//! chunks is formatted in parallel into per-chunk buffers and written in order while the next
//! wave is formatted, so that the bytes are those of a serial loop and the memory two waves,
//! not the whole file.

use std::io::{self, Write};
use std::ops::Range;

use rayon::prelude::*;

/// Records per chunk: about 100 kB of an OBJ's `v` or `f` lines, enough to make a chunk's
/// scheduling cost negligible.
const RECORDS_PER_CHUNK: usize = 4096;

/// Chunks per worker thread in a wave: more than one, so that a thread slowed by another
/// process does not hold the wave up alone.
const CHUNKS_PER_THREAD: usize = 2;

/// Writes records `0..count` in order, record `i` appended to a buffer by `record(i, buffer)`.
/// Each wave is written while the next one is formatted; the two waves' buffers take about
/// `2 × 2 × threads × 4096` records' bytes.
pub(in crate::io) fn write_records(
    out: &mut impl Write,
    count: usize,
    record: impl Fn(usize, &mut Vec<u8>) + Sync,
) -> io::Result<()> {
    write_chunks(out, count, |records, buffer| {
        each_record(records, buffer, &record)
    })
}

/// Appends records `records` to `buffer` by `record(i, buffer)`, with room for them all made
/// after the first: at the first record's length and a quarter more (growing from empty would
/// copy the chunk about once more).
pub(in crate::io) fn each_record(
    mut records: Range<usize>,
    buffer: &mut Vec<u8>,
    mut record: impl FnMut(usize, &mut Vec<u8>),
) {
    if let Some(i) = records.next() {
        record(i, buffer);
        buffer.reserve(buffer.len() * records.len() / 4 * 5);
    }
    records.for_each(|i| record(i, buffer));
}

/// [`write_records`] a chunk at a time: `chunk(records, buffer)` appends records `records`
/// to the empty `buffer` (a chunk's records are formatted in order on one thread, so that
/// they can share work, as [`super::float_text::F32Text`] does).
pub(in crate::io) fn write_chunks(
    out: &mut impl Write,
    count: usize,
    chunk: impl Fn(Range<usize>, &mut Vec<u8>) + Sync,
) -> io::Result<()> {
    let wave = (CHUNKS_PER_THREAD * rayon::current_num_threads()).max(1);
    // Whole waves of chunks of one size, so that no thread idles through a last wave of
    // fewer chunks than threads.
    let chunks = count.div_ceil(RECORDS_PER_CHUNK).div_ceil(wave) * wave;
    let per_chunk = count.div_ceil(chunks.max(1)).max(1);
    let chunks = count.div_ceil(per_chunk);
    let wave = wave.clamp(1, chunks.max(1));
    // Formats the chunks from `first` into `buffers`, one each.
    let format = |first: usize, buffers: &mut [Vec<u8>]| {
        buffers.par_iter_mut().enumerate().for_each(|(k, buffer)| {
            buffer.clear();
            let start = (first + k) * per_chunk;
            chunk(start..count.min(start + per_chunk), buffer);
        });
    };
    let (mut ready, mut next) = (vec![Vec::new(); wave], vec![Vec::new(); wave]);
    // Chunks formatted in `ready`, not yet written.
    let mut formatted = 0;
    for first in (0..chunks).step_by(wave) {
        let these = wave.min(chunks - first);
        if formatted == 0 {
            format(first, &mut ready[..these]);
        } else {
            // The writing stays on this thread (`out` need not be `Send`); the formatting is
            // spawned onto the current pool.
            let mut written = Ok(());
            rayon::in_place_scope(|s| {
                s.spawn(|_| format(first, &mut next[..these]));
                written = ready[..formatted].iter().try_for_each(|b| out.write_all(b));
            });
            written?;
            std::mem::swap(&mut ready, &mut next);
        }
        formatted = these;
    }
    ready[..formatted].iter().try_for_each(|b| out.write_all(b))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Record counts around the chunk and wave sizes, on 1 and 3 threads: the bytes of the
    /// serial loop.
    #[test]
    fn records_come_out_in_order_whatever_the_threads() {
        let line = |i: usize, b: &mut Vec<u8>| b.extend_from_slice(format!("r {i}\n").as_bytes());
        for threads in [1, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            for count in [0, 1, 4095, 4096, 4097, 6 * 4096 + 17, 20 * 4096] {
                let mut serial = Vec::new();
                (0..count).for_each(|i| line(i, &mut serial));
                let mut parallel = Vec::new();
                pool.install(|| write_records(&mut parallel, count, line))
                    .unwrap();
                assert!(parallel == serial, "{count} records on {threads} threads");
            }
        }
    }
}
