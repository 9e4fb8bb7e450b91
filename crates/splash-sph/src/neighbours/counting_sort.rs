//! Stable counting sort by bucket on all threads: a few consecutive chunks of the items each
//! count their buckets, the counts are laid out bucket by bucket with the chunks in input
//! order, and each chunk scatters its items to its own slots. Within a bucket the items keep
//! their input order whatever the number of chunks, so the result is the serial one.

use rayon::prelude::*;

/// Items per chunk below which more chunks cost more than they save.
const MIN_CHUNK: usize = 1 << 16;

/// Chunks at most: each holds a count per bucket.
const MAX_CHUNKS: usize = 4;

/// `place(i, &items[i])` for each item, the bucket (below `buckets`) and value it puts
/// there, or `None` to leave it out: the values ordered by bucket, stably, with the
/// `buckets + 1` offsets where each bucket starts and the last ends.
///
/// `place` runs twice per item (to count, then to place), and `items` must be fewer than
/// `u32::MAX`.
///
/// # Safety
///
/// `place` must give the same answer both times it is asked about an item (a function of its
/// arguments): the chunks write their slots unsynchronised, sized by the first answers.
pub(crate) unsafe fn sort_by_bucket<T, U, P>(
    items: &[T],
    buckets: usize,
    place: P,
) -> (Vec<U>, Vec<u32>)
where
    T: Sync,
    U: Send,
    P: Fn(usize, &T) -> Option<(usize, U)> + Sync,
{
    let mut sorted = Vec::new();
    // SAFETY: the caller's promise about `place`.
    let offsets = unsafe { sort_by_bucket_into(items, buckets, place, &mut sorted) };
    (sorted, offsets)
}

/// [`sort_by_bucket`] into `sorted`, whose contents it replaces: a caller can allocate it
/// before the items, so that the items, freed, leave no hole below it in the heap.
///
/// # Safety
///
/// As for [`sort_by_bucket`].
pub(crate) unsafe fn sort_by_bucket_into<T, U, P>(
    items: &[T],
    buckets: usize,
    place: P,
    sorted: &mut Vec<U>,
) -> Vec<u32>
where
    T: Sync,
    U: Send,
    P: Fn(usize, &T) -> Option<(usize, U)> + Sync,
{
    assert!(items.len() < u32::MAX as usize, "offsets are u32");
    let chunks = (items.len() / MIN_CHUNK)
        .clamp(1, MAX_CHUNKS)
        .min(rayon::current_num_threads());
    let chunk_len = items.len().div_ceil(chunks).max(1);
    // counts[c * buckets + b]: items of chunk c in bucket b, then where chunk c's next one goes.
    let mut counts = vec![0u32; chunks * buckets];
    counts
        .par_chunks_mut(buckets.max(1))
        .zip(items.par_chunks(chunk_len))
        .enumerate()
        .for_each(|(c, (counts, items))| {
            let first = c * chunk_len;
            for (i, item) in items.iter().enumerate() {
                if let Some((b, _)) = place(first + i, item) {
                    counts[b] += 1;
                }
            }
        });
    let mut offsets = Vec::with_capacity(buckets + 1);
    let mut start = 0u32;
    for b in 0..buckets {
        offsets.push(start);
        for c in 0..chunks {
            let count = &mut counts[c * buckets + b];
            (*count, start) = (start, start + *count);
        }
    }
    offsets.push(start);
    let kept = start as usize;
    sorted.clear();
    sorted.reserve(kept);
    let out = SharedSlots(sorted.as_mut_ptr());
    counts
        .par_chunks_mut(buckets.max(1))
        .zip(items.par_chunks(chunk_len))
        .enumerate()
        .for_each(|(c, (next, items))| {
            let (out, first) = (&out, c * chunk_len);
            for (i, item) in items.iter().enumerate() {
                if let Some((b, value)) = place(first + i, item) {
                    // SAFETY: chunk c's slots for bucket b run from its start to the next
                    // chunk's (or bucket's) start, and it places exactly as many values there
                    // as it counted (the caller's promise about `place`): every slot below
                    // `kept`, within the capacity reserved, is written once, by one chunk.
                    unsafe { out.0.add(next[b] as usize).write(value) };
                    next[b] += 1;
                }
            }
        });
    // SAFETY: every one of the `kept` slots was written (see above).
    unsafe { sorted.set_len(kept) };
    offsets
}

/// The output's slots, written by several chunks at disjoint positions.
struct SharedSlots<U>(*mut U);

// SAFETY: the chunks write disjoint slots (see `sort_by_bucket`).
unsafe impl<U: Send> Sync for SharedSlots<U> {}

#[cfg(test)]
mod tests {
    use super::*;

    /// The serial stable counting sort the parallel one must equal.
    fn serial<T: Copy>(
        items: &[T],
        buckets: usize,
        bucket: impl Fn(&T) -> Option<usize>,
    ) -> (Vec<T>, Vec<u32>) {
        let mut each = vec![Vec::new(); buckets];
        for item in items {
            if let Some(b) = bucket(item) {
                each[b].push(*item);
            }
        }
        let mut offsets = vec![0];
        offsets.extend(each.iter().scan(0, |end, b| {
            *end += b.len() as u32;
            Some(*end)
        }));
        (each.concat(), offsets)
    }

    #[test]
    fn equals_the_serial_sort_on_any_number_of_threads() {
        let mut state = 7u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) as u32
        };
        for (n, buckets) in [(0, 1), (1, 3), (1000, 7), (300_000, 64), (300_000, 5000)] {
            // Items tagged with their index, so the order within a bucket shows; those in
            // bucket 0 are left out.
            let items: Vec<(u32, u32)> = (0..n).map(|i| (next() % buckets as u32, i)).collect();
            let bucket = |&(k, _): &(u32, u32)| (k != 0).then_some(k as usize);
            let expected = serial(&items, buckets, bucket);
            let place = |i: usize, item: &(u32, u32)| {
                assert_eq!(item.1 as usize, i, "place is given each item's index");
                bucket(item).map(|b| (b, *item))
            };
            for threads in [1, 2, 3, 4] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                // SAFETY: `place` is a function of its arguments.
                let got = pool.install(|| unsafe { sort_by_bucket(&items, buckets, place) });
                assert_eq!(
                    got, expected,
                    "{n} items, {buckets} buckets, {threads} threads"
                );
            }
        }
    }
}
