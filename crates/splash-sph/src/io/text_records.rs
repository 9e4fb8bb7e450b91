//! Text payloads formatted on all threads: the records (lines) are cut into chunks, a wave of
//! chunks is formatted in parallel into per-chunk buffers, then written in order, so that the
//! bytes are those of a serial loop and the memory is one wave, not the whole file.

use std::io::{self, Write};

use rayon::prelude::*;

/// Records per chunk: about 100 kB of an OBJ's `v` or `f` lines, enough to make a chunk's
/// scheduling cost negligible.
const RECORDS_PER_CHUNK: usize = 4096;

/// Chunks per worker thread in a wave: more than one, so that a thread slowed by another
/// process does not hold the wave up alone.
const CHUNKS_PER_THREAD: usize = 2;

/// Writes records `0..count` in order, record `i` appended to a buffer by `record(i, buffer)`.
/// The wave's buffers take about `2 × threads × 4096` records' bytes.
pub(super) fn write_records(
    out: &mut impl Write,
    count: usize,
    record: impl Fn(usize, &mut Vec<u8>) + Sync,
) -> io::Result<()> {
    let chunks = count.div_ceil(RECORDS_PER_CHUNK);
    let wave = (CHUNKS_PER_THREAD * rayon::current_num_threads()).clamp(1, chunks.max(1));
    let mut buffers: Vec<Vec<u8>> = vec![Vec::new(); wave];
    for first in (0..chunks).step_by(wave) {
        let these = wave.min(chunks - first);
        buffers[..these]
            .par_iter_mut()
            .enumerate()
            .for_each(|(k, buffer)| {
                buffer.clear();
                let start = (first + k) * RECORDS_PER_CHUNK;
                for i in start..count.min(start + RECORDS_PER_CHUNK) {
                    record(i, buffer);
                }
            });
        for buffer in &buffers[..these] {
            out.write_all(buffer)?;
        }
    }
    Ok(())
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
