//! The detector's worker threads: per-cluster quad fitting and per-quad decoding are
//! independent, so they are shared out over a thread pool when `nthreads` > 1. Results keep
//! the input order, so the output is the same for any number of threads.

use rayon::prelude::*;

/// One thread (the caller's), or a pool of `nthreads`.
#[derive(Debug)]
pub struct Workers {
    pool: Option<rayon::ThreadPool>,
}

impl Workers {
    /// Work on the calling thread only.
    pub fn single() -> Self {
        Workers { pool: None }
    }

    /// A pool of `n` threads, or the calling thread when `n` ≤ 1 (or if the pool cannot be
    /// made: fewer threads only cost time).
    pub fn new(n: usize) -> Self {
        let pool = (n > 1).then(|| rayon::ThreadPoolBuilder::new().num_threads(n).build().ok()).flatten();
        Workers { pool }
    }

    /// `items.iter().filter_map(f)`, in order, spread over the pool.
    pub fn filter_map<T: Sync, R: Send>(&self, items: &[T], f: impl Fn(&T) -> Option<R> + Sync + Send) -> Vec<R> {
        match &self.pool {
            None => items.iter().filter_map(f).collect(),
            // Small pieces balance clusters of very different sizes.
            Some(pool) => pool.install(|| items.par_iter().with_max_len(4).filter_map(f).collect()),
        }
    }
}
