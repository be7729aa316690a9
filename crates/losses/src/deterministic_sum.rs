//! Parallel `f64` sums that give the same bits for any thread count.
//!
//! rayon's `sum` splits work adaptively, so the order of floating-point additions (and thus
//! the last bits of the result) depends on scheduling. Here the items are cut into fixed
//! chunks, each chunk is summed sequentially in parallel, and the chunk sums are added in
//! order: the association is fixed, so the result is deterministic.

use rayon::prelude::*;

/// Chunk length: large enough to amortise scheduling, small enough to balance 2-64 cores.
const CHUNK: usize = 4096;

/// Σ_{i<n} term(i), computed in parallel with a fixed association.
pub(crate) fn deterministic_sum<F>(n: usize, term: F) -> f64
where
    F: Fn(usize) -> f64 + Sync,
{
    let chunks = n.div_ceil(CHUNK);
    let partial: Vec<f64> = (0..chunks)
        .into_par_iter()
        .map(|c| {
            let start = c * CHUNK;
            let end = (start + CHUNK).min(n);
            (start..end).map(&term).sum::<f64>()
        })
        .collect();
    partial.iter().sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_bits_on_one_and_many_threads() {
        let term = |i: usize| 1.0 / (1.0 + i as f64).sqrt();
        let n = 100_003;
        let many = deterministic_sum(n, term);
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| deterministic_sum(n, term));
        assert_eq!(many.to_bits(), one.to_bits());
        let sequential: f64 = (0..n).map(term).sum();
        assert!((many - sequential).abs() < 1e-9 * sequential);
    }
}
