//! The worker threads a `threads` setting asks for, shared by recon, iso and preview.

use std::sync::Arc;

use crate::error::{Error, Result};

/// A pool of `threads` workers, or None for rayon's global pool (all cores).
pub(crate) fn worker_pool(threads: Option<usize>) -> Result<Option<Arc<rayon::ThreadPool>>> {
    match threads {
        Some(0) => Err(Error::config("threads must be at least 1")),
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .map(|pool| Some(Arc::new(pool)))
            .map_err(|e| Error::config(format!("cannot start {n} worker threads: {e}"))),
        None => Ok(None),
    }
}
