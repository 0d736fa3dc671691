//! The detector's worker threads. Two kinds of work are shared out over a thread pool when
//! `nthreads` > 1:
//! - the image stages (decimation, threshold, regions, clusters) by bands of rows, each band
//!   writing only its own rows ([`Workers::rows_mut`], [`Workers::map`]);
//! - per-cluster quad fitting and per-quad decoding, which are independent
//!   ([`Workers::filter_map`]).
//!
//! Results keep the input order, so the output is the same for any number of threads.

use rayon::prelude::*;
use std::ops::Range;

/// Bands per thread: more bands than threads balance a frame whose tags crowd into one part.
const BANDS_PER_THREAD: usize = 4;
/// The fewest rows a band holds: a seam between bands costs about a row's work.
const MIN_BAND_ROWS: usize = 32;

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

    /// How many threads work: 1 without a pool.
    pub fn threads(&self) -> usize {
        self.pool.as_ref().map_or(1, rayon::ThreadPool::current_num_threads)
    }

    /// `items.iter().filter_map(f)`, in order, spread over the pool.
    pub fn filter_map<T: Sync, R: Send>(&self, items: &[T], f: impl Fn(&T) -> Option<R> + Sync + Send) -> Vec<R> {
        match &self.pool {
            None => items.iter().filter_map(f).collect(),
            // Small pieces balance clusters of very different sizes.
            Some(pool) => pool.install(|| items.par_iter().with_max_len(4).filter_map(f).collect()),
        }
    }

    /// `items.iter().map(f)`, in order, each item a piece of its own for the pool: for a few
    /// items of very different cost.
    pub fn map_each<T: Sync, R: Send>(&self, items: &[T], f: impl Fn(&T) -> R + Sync + Send) -> Vec<R> {
        match &self.pool {
            None => items.iter().map(f).collect(),
            Some(pool) => pool.install(|| items.par_iter().with_max_len(1).map(f).collect()),
        }
    }

    /// The bands `rows` rows are split into: one without a pool, else up to four per thread
    /// of at least 32 rows each, top to bottom.
    pub fn band_ranges(&self, rows: usize) -> Vec<Range<usize>> {
        let n = match self.pool {
            None => 1,
            Some(_) => (self.threads() * BANDS_PER_THREAD).min(rows / MIN_BAND_ROWS).max(1),
        };
        (0..n).map(|k| k * rows / n..(k + 1) * rows / n).collect()
    }

    /// `f(rows, their data)` over bands of `data`'s rows of `row_len` items each, every band
    /// writing only its own rows.
    pub fn rows_mut<T: Send>(&self, data: &mut [T], row_len: usize, f: impl Fn(Range<usize>, &mut [T]) + Sync + Send) {
        let rows = data.len().checked_div(row_len).unwrap_or(0);
        let ranges = self.band_ranges(rows);
        let mut pieces = Vec::with_capacity(ranges.len());
        let mut rest = &mut data[..rows * row_len];
        for r in &ranges {
            let (piece, tail) = rest.split_at_mut(r.len() * row_len);
            pieces.push((r.clone(), piece));
            rest = tail;
        }
        self.map(pieces, |(r, p)| f(r, p));
    }

    /// `f` on each of `items`, one item a task; the results in the items' order.
    pub fn map<T: Send, R: Send>(&self, items: Vec<T>, f: impl Fn(T) -> R + Sync + Send) -> Vec<R> {
        match &self.pool {
            None => items.into_iter().map(f).collect(),
            Some(pool) => pool.install(|| items.into_par_iter().with_max_len(1).map(f).collect()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_cover_every_row_once_in_order() {
        for threads in [1, 2, 3] {
            let w = Workers::new(threads);
            for rows in [0, 1, 31, 32, 64, 100, 1080] {
                let bands = w.band_ranges(rows);
                assert!(!bands.is_empty());
                assert_eq!(bands.first().map(|r| r.start), Some(0));
                assert_eq!(bands.last().map(|r| r.end), Some(rows));
                assert!(bands.windows(2).all(|p| p[0].end == p[1].start), "{bands:?}");
                if threads > 1 && rows >= 64 {
                    assert!(bands.len() > 1, "{rows} rows, {threads} threads: {bands:?}");
                }
            }
            let mut data = vec![0usize; 7 * 300];
            w.rows_mut(&mut data, 7, |rows, piece| {
                for (y, row) in rows.zip(piece.chunks_exact_mut(7)) {
                    row.fill(y);
                }
            });
            assert!(data.chunks_exact(7).enumerate().all(|(y, r)| r.iter().all(|&v| v == y)));
        }
    }
}
