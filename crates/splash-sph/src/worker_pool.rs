//! The worker threads a `threads` setting asks for: one policy for the command line, Python
//! and the Blender add-on (which runs either). A run's work goes to `threads` workers, kept
//! between calls ([`install`]); a sequence reads on one thread of its own and writes on
//! another. A [`Reconstructor`](crate::Reconstructor), an isosurface or a preview given
//! `threads` in its configuration keeps a pool of its own as long as it lives.

use std::cell::RefCell;
use std::collections::HashMap;
use std::collections::hash_map::Entry;
use std::rc::Rc;
use std::sync::Arc;

use rayon::ThreadPool;

use crate::error::{Error, Result};

/// A pool of `threads` workers, or None for the caller's pool (rayon's global pool, all
/// cores, outside any).
pub(crate) fn worker_pool(threads: Option<usize>) -> Result<Option<Arc<ThreadPool>>> {
    threads
        .map(start)
        .transpose()
        .map(|pool| pool.map(Arc::new))
}

fn start(n: usize) -> Result<ThreadPool> {
    if n == 0 {
        return Err(Error::config("threads must be at least 1"));
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .map_err(|e| Error::config(format!("cannot start {n} worker threads: {e}")))
}

thread_local! {
    /// Per calling thread: Python threads reconstructing at once each get the workers they
    /// asked for, rather than queueing for shared ones. They end with the calling thread.
    static POOLS: RefCell<HashMap<usize, Rc<ThreadPool>>> = RefCell::new(HashMap::new());
}

/// Runs `f` on `threads` workers, kept for this calling thread's later calls with the same
/// count, or in the caller's pool when None. A pool started for one call starts cold (its
/// threads' stacks, caches and allocator arenas): on a 44k-particle frame that added 15 ms
/// to an 80 ms reconstruction, every call of a loop over frames.
pub fn install<T: Send>(threads: Option<usize>, f: impl FnOnce() -> T + Send) -> Result<T> {
    let Some(n) = threads else {
        return Ok(f());
    };
    let pool = POOLS.with_borrow_mut(|pools| match pools.entry(n) {
        Entry::Occupied(kept) => Ok(kept.get().clone()),
        Entry::Vacant(slot) => Ok(slot.insert(Rc::new(start(n)?)).clone()),
    })?;
    Ok(pool.install(f))
}

#[cfg(test)]
mod tests {
    use super::install;

    #[test]
    fn a_call_runs_on_the_workers_asked_for_and_keeps_them() {
        assert_eq!(install(Some(3), rayon::current_num_threads).unwrap(), 3);
        let first = install(Some(2), rayon::current_thread_index).unwrap();
        assert!(first.is_some());
        // The same pool again: its two workers, not a new pool's.
        let ids = || rayon::broadcast(|_| std::thread::current().id());
        let a = install(Some(2), ids).unwrap();
        let b = install(Some(2), ids).unwrap();
        assert_eq!(a.len(), 2);
        assert_eq!(
            a.iter().collect::<std::collections::HashSet<_>>(),
            b.iter().collect()
        );
        assert!(install(Some(0), || ()).is_err());
        assert_eq!(install(None, || 7).unwrap(), 7);
    }
}
