//! Per-pair work of the contact terms, split into fixed chunks balanced by
//! vertex count.
//!
//! A hull pair's cost (GJK, the inner plane solve, the pose contraction) is
//! linear in its vertex count `w_k = |V_a| + |V_b|`. The pairs are cut into
//! `c` contiguous chunks of nearly equal weight: chunk `j` ends at the first
//! pair whose prefix sum reaches `⌈(j + 1) W / c⌉` (`W = Σ w_k`), so the
//! partition depends only on the weights and `c` (the thread count). Each
//! pair is evaluated on its own (its own scratch, no shared state) and the
//! results are handed back in pair order, so the caller's reduction — in
//! pair order — is bitwise the same for any partition and thread count.
//!
//! Below [`PARALLEL_MIN_WEIGHT`] vertices in all, the pairs run on the
//! calling thread: handing a few microseconds of work to the thread pool
//! (wake a worker, wait on a latch) cost more than the work itself — 15 % of a
//! step with eight links per chain, measured with `perf` (scheduler and
//! futex time).

use rayon::prelude::*;

/// Total vertex count of a batch of pairs below which it is evaluated
/// sequentially (about 30 box–box pairs, ~50 µs of work).
pub const PARALLEL_MIN_WEIGHT: usize = 512;

/// Persistent buffers of [`PairWork::map`] (no allocation once warm).
#[derive(Clone, Debug)]
pub struct PairWork<R> {
    /// Per-chunk results (in pair order within the chunk).
    chunks: Vec<Vec<R>>,
    /// Chunk `j` is `items[bounds[j]..bounds[j + 1]]`.
    bounds: Vec<usize>,
}

impl<R> Default for PairWork<R> {
    fn default() -> Self {
        PairWork {
            chunks: Vec::new(),
            bounds: Vec::new(),
        }
    }
}

/// Chunk bounds of `weights` for `c` chunks (see the module documentation):
/// `bounds[0] = 0`, `bounds[c] = weights.len()`, non-decreasing.
pub fn balanced_bounds(
    weights: impl Iterator<Item = usize> + Clone,
    c: usize,
    out: &mut Vec<usize>,
) {
    let n = weights.clone().count();
    let total: usize = weights.clone().sum();
    let c = c.max(1);
    out.clear();
    out.push(0);
    let (mut prefix, mut k) = (0usize, 0usize);
    let mut it = weights;
    for j in 1..c {
        let target = (j * total).div_ceil(c);
        while k < n && prefix < target {
            prefix += it.next().unwrap_or(0);
            k += 1;
        }
        out.push(k);
    }
    out.push(n);
}

impl<R: Send> PairWork<R> {
    /// `out = items.map(f)` in item order, with `init()` scratch per chunk;
    /// parallel in vertex-balanced chunks when `Σ weight ≥`
    /// [`PARALLEL_MIN_WEIGHT`] and the pool has more than one thread.
    pub fn map<T: Sync, S>(
        &mut self,
        items: &[T],
        weight: impl Fn(&T) -> usize + Sync,
        init: impl Fn() -> S + Sync,
        f: impl Fn(&mut S, &T) -> R + Sync,
        out: &mut Vec<R>,
    ) {
        out.clear();
        let threads = rayon::current_num_threads();
        let total: usize = items.iter().map(&weight).sum();
        if threads < 2 || items.len() < 2 || total < PARALLEL_MIN_WEIGHT {
            let mut scratch = init();
            out.extend(items.iter().map(|x| f(&mut scratch, x)));
            return;
        }
        balanced_bounds(items.iter().map(&weight), threads, &mut self.bounds);
        self.chunks.resize_with(threads, Vec::new);
        let bounds = &self.bounds;
        self.chunks
            .par_iter_mut()
            .enumerate()
            .for_each(|(j, chunk)| {
                chunk.clear();
                let part = &items[bounds[j]..bounds[j + 1]];
                if part.is_empty() {
                    return;
                }
                let mut scratch = init();
                chunk.extend(part.iter().map(|x| f(&mut scratch, x)));
            });
        for chunk in &mut self.chunks {
            out.append(chunk);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounds_cover_in_order_and_balance() {
        let w = [8usize, 8, 16, 8, 100, 8, 8, 8, 24, 8];
        for c in 1..6 {
            let mut b = Vec::new();
            balanced_bounds(w.iter().copied(), c, &mut b);
            assert_eq!(b.len(), c + 1);
            assert_eq!((b[0], b[c]), (0, w.len()));
            assert!(b.windows(2).all(|x| x[0] <= x[1]));
        }
        let mut b = Vec::new();
        balanced_bounds([10usize; 8].into_iter(), 2, &mut b);
        assert_eq!(b, vec![0, 4, 8]);
        balanced_bounds(std::iter::empty(), 3, &mut b);
        assert_eq!(b, vec![0, 0, 0, 0]);
    }

    /// Sequential and parallel paths give the same results in item order.
    #[test]
    fn map_keeps_item_order_on_both_paths() {
        let mut work = PairWork::default();
        for n in [0usize, 1, 3, 40, 300] {
            let items: Vec<usize> = (0..n).collect();
            let mut out = Vec::new();
            work.map(
                &items,
                |&i| 8 + i % 17,
                || 0usize,
                |calls, &i| {
                    *calls += 1;
                    (i * i) as f64 / 7.0
                },
                &mut out,
            );
            let want: Vec<f64> = items.iter().map(|&i| (i * i) as f64 / 7.0).collect();
            assert_eq!(out, want, "n = {n}");
        }
    }
}
