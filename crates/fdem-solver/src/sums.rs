//! Sums over the nodes or elements that do not depend on the thread count:
//! fixed chunks of [`CHUNK`] indices, each summed in index order, added up
//! along a binary tree whose shape depends on the length alone.

use std::ops::Range;

use crate::CHUNK;

/// `Σ leaf(chunk)` over the chunks of `0..n` ([`CHUNK`] indices each, the
/// last one shorter), `zero` for `n = 0`. Each leaf sums its range in index
/// order; the chunks are added along a tree that halves the chunk range at
/// fixed points, its two halves worked out side by side
/// ([`rayon::join`], in the current pool) and added left + right. The
/// result depends on `n` and the terms only, never on the thread count, and
/// nothing is allocated: the energy watchdog calls this inside the time
/// loop, where a serial pass over the nodes would be the one part of a step
/// that more threads cannot shorten.
pub(crate) fn chunk_tree_sum<T: Send>(
    n: usize,
    zero: T,
    leaf: &(impl Fn(Range<usize>) -> T + Sync),
    add: &(impl Fn(T, T) -> T + Sync),
) -> T {
    fn tree<T: Send>(
        chunks: Range<usize>,
        n: usize,
        leaf: &(impl Fn(Range<usize>) -> T + Sync),
        add: &(impl Fn(T, T) -> T + Sync),
    ) -> T {
        if chunks.len() == 1 {
            return leaf(chunks.start * CHUNK..n.min(chunks.end * CHUNK));
        }
        let mid = chunks.start + chunks.len() / 2;
        let (a, b) = rayon::join(|| tree(chunks.start..mid, n, leaf, add), || tree(mid..chunks.end, n, leaf, add));
        add(a, b)
    }
    if n == 0 {
        return zero;
    }
    tree(0..n.div_ceil(CHUNK), n, leaf, add)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The same bits on 1, 2, 3 and 7 threads, for lengths round the chunk
    /// size; the sum of exactly representable terms is exact.
    #[test]
    fn the_sum_does_not_depend_on_the_thread_count() {
        let terms: Vec<f64> = (0..10 * CHUNK + 17).map(|i| ((i * 7919) % 1000) as f64 * 1e-3 + 1.0 / 3.0).collect();
        for n in [0, 1, CHUNK - 1, CHUNK, CHUNK + 1, 3 * CHUNK + 5, terms.len()] {
            let sum = |threads: usize| {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                pool.install(|| {
                    chunk_tree_sum(n, 0.0, &|r: Range<usize>| r.map(|i| terms[i]).fold(0.0, |a, b| a + b), &|a, b| {
                        a + b
                    })
                })
            };
            let one = sum(1);
            for threads in [2, 3, 7] {
                assert_eq!(sum(threads).to_bits(), one.to_bits(), "n = {n}, {threads} threads");
            }
            let exact: f64 = (0..n).map(|i| ((i * 7919) % 1000) as f64).sum();
            assert!((one - (exact * 1e-3 + n as f64 / 3.0)).abs() <= 1e-9 * (1.0 + one.abs()), "n = {n}");
        }
        let count = chunk_tree_sum(terms.len(), 0, &|r: Range<usize>| r.len(), &|a, b| a + b);
        assert_eq!(count, terms.len());
    }
}
