//! Worker pools kept between calls. A pool started for one call starts cold (its threads'
//! stacks, caches and allocator arenas): on a 44k-particle frame that added 15 ms to a 80 ms
//! reconstruction, every call of a loop over frames.

use std::cell::RefCell;
use std::collections::HashMap;
use std::rc::Rc;

use rayon::{ThreadPool, ThreadPoolBuilder};
use splash_sph::Error;

thread_local! {
    /// Per calling thread: Python threads reconstructing at once each get the workers they
    /// asked for, rather than queueing for shared ones. They end with the calling thread.
    static POOLS: RefCell<HashMap<usize, Rc<ThreadPool>>> = RefCell::new(HashMap::new());
}

/// Runs `f` on `threads` workers, or in rayon's global pool (all cores) when None.
pub fn install<T: Send>(
    threads: Option<usize>,
    f: impl FnOnce() -> T + Send,
) -> splash_sph::Result<T> {
    let Some(n) = threads else {
        return Ok(f());
    };
    let pool = POOLS.with_borrow_mut(|pools| {
        if let Some(pool) = pools.get(&n) {
            return Ok(pool.clone());
        }
        let pool = ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .map_err(|e| Error::Config(format!("cannot start {n} worker threads: {e}")))?;
        Ok(pools.entry(n).or_insert(Rc::new(pool)).clone())
    })?;
    Ok(pool.install(f))
}
