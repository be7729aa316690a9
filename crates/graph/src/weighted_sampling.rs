//! Weighted sampling without replacement: the multinomial point sampler of the neural mesh
//! simplifier (thesis ch. 6.3, "samples nodes under the assumption of a multinomial
//! distribution" from learned inclusion scores), in O(N) expected time whatever the sample size
//! (the thesis' argument against FPS's O(N·k)).
//!
//! Algorithm: Efraimidis & Spirakis 2006, "Weighted random sampling with a reservoir", IPL 97(5):
//! give item `i` the key `−ln(u_i) / w_i` with `u_i` uniform in (0, 1] (an exponential variate
//! of rate `w_i`); the `k` smallest keys, in increasing order, are distributed exactly as `k`
//! successive draws without replacement with probabilities proportional to the remaining
//! weights. The `k` smallest are found with `select_nth_unstable_by` (O(N) expected) and then
//! sorted (O(k log k)).
//!
//! # Conventions
//! - `weights: #N` (`f32`, finite, `>= 0`); the result is `k` distinct `u32` indices in draw
//!   order, so any prefix is itself a valid sample.
//! - Zero weights are drawn only after every positive weight is taken, uniformly among
//!   themselves (as if their weights were an infinitesimal equal `ε`).
//! - Uniform sampling ([`uniform_sampling`]) is the case of equal weights and gives the same
//!   result as [`weighted_sampling`] with all weights 1.
//! - Deterministic: the uniforms come from per-chunk generators
//!   `StdRng::seed_from_u64(mix(seed, chunk))` over fixed 4096-element chunks, so the result
//!   depends only on `(weights, k, seed)`, not on the thread count.

use rand::{Rng, SeedableRng, rngs::StdRng};
use rayon::prelude::*;

use crate::{Error, Result};

/// Items per seeded generator (fixed: changing it changes the samples).
const CHUNK: usize = 4096;

/// A sort key: `(zero-weight class, exponential key, index)`, compared lexicographically.
type Key = (bool, f64, u32);

/// The seed of chunk `c`'s generator: SplitMix64 of the seed and chunk index.
fn chunk_seed(seed: u64, chunk: u64) -> u64 {
    let mut z = seed ^ chunk.wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

fn cmp_keys(a: &Key, b: &Key) -> std::cmp::Ordering {
    a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)).then(a.2.cmp(&b.2))
}

/// Keys for `n` items with weights given by `weight(i)` (checked by the caller), then the `k`
/// smallest in increasing order.
fn sample_by_keys(n: usize, k: usize, seed: u64, weight: impl Fn(usize) -> f32 + Sync) -> Vec<u32> {
    let mut keys: Vec<Key> = vec![(false, 0.0, 0); n];
    keys.par_chunks_mut(CHUNK)
        .enumerate()
        .for_each(|(c, chunk)| {
            let mut rng = StdRng::seed_from_u64(chunk_seed(seed, c as u64));
            for (j, key) in chunk.iter_mut().enumerate() {
                let i = c * CHUNK + j;
                // 1 − [0, 1) is (0, 1], so the logarithm is finite.
                let e = -(1.0 - rng.random::<f64>()).ln();
                let w = f64::from(weight(i));
                *key = if w > 0.0 {
                    (false, e / w, i as u32)
                } else {
                    (true, e, i as u32)
                };
            }
        });
    if k < n {
        keys.select_nth_unstable_by(k, cmp_keys);
        keys.truncate(k);
    }
    keys.par_sort_unstable_by(cmp_keys);
    keys.into_iter().map(|key| key.2).collect()
}

fn check_k(k: usize, n: usize) -> Result<()> {
    if k > n {
        return Err(Error::InvalidParameter {
            name: "k",
            message: format!("cannot draw {k} distinct items out of {n}"),
        });
    }
    if u32::try_from(n).is_err() {
        return Err(Error::InvalidParameter {
            name: "weights",
            message: format!("{n} items do not fit u32 indices"),
        });
    }
    Ok(())
}

/// Draws `k` distinct indices of `weights: #N` without replacement, each draw with probability
/// proportional to the weights still in the pool (ch. 6.3's multinomial sampling of inclusion
/// scores). O(N) expected plus O(k log k), parallel, seeded.
///
/// Errors when `k > N` or a weight is negative, NaN or infinite.
///
/// ```
/// use meshgnn_graph::weighted_sampling;
/// // Weight 0 is drawn only after all positive weights are used up.
/// let picked = weighted_sampling(&[0.0, 1.0, 3.0], 3, 42)?;
/// assert_eq!(picked.len(), 3);
/// assert_eq!(picked[2], 0);
/// assert_eq!(weighted_sampling(&[0.0, 1.0, 3.0], 3, 42)?, picked); // same seed, same draw
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn weighted_sampling(weights: &[f32], k: usize, seed: u64) -> Result<Vec<u32>> {
    check_k(k, weights.len())?;
    if let Some((index, &value)) = weights
        .iter()
        .enumerate()
        .find(|(_, w)| !(w.is_finite() && **w >= 0.0))
    {
        return Err(Error::InvalidWeight { index, value });
    }
    Ok(sample_by_keys(weights.len(), k, seed, |i| weights[i]))
}

/// Draws `k` distinct indices of `0..n` uniformly without replacement (random sampling, the
/// baseline of ch. 5-6 and the equal-weight case of [`weighted_sampling`], with identical
/// output for the same seed). O(n) expected, parallel, seeded.
///
/// ```
/// use meshgnn_graph::{uniform_sampling, weighted_sampling};
/// let picked = uniform_sampling(10, 4, 7)?;
/// assert_eq!(picked, weighted_sampling(&[1.0; 10], 4, 7)?);
/// assert!(uniform_sampling(3, 4, 7).is_err());
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn uniform_sampling(n: usize, k: usize, seed: u64) -> Result<Vec<u32>> {
    check_k(k, n)?;
    Ok(sample_by_keys(n, k, seed, |_| 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frequencies(weights: &[f32], k: usize, trials: u64) -> Vec<f64> {
        let mut count = vec![0usize; weights.len()];
        for seed in 0..trials {
            for i in weighted_sampling(weights, k, seed).unwrap() {
                count[i as usize] += 1;
            }
        }
        count.iter().map(|&c| c as f64 / trials as f64).collect()
    }

    /// Tolerance: 5 standard deviations of a frequency over `trials` (p(1−p) ≤ 1/4).
    fn tolerance(trials: u64) -> f64 {
        5.0 * 0.5 / (trials as f64).sqrt()
    }

    #[test]
    fn single_draw_frequencies_are_proportional_to_weights() {
        let w = [1.0f32, 2.0, 3.0, 4.0, 0.5];
        let total: f32 = w.iter().sum();
        let trials = 20_000;
        for (f, &wi) in frequencies(&w, 1, trials).iter().zip(&w) {
            assert!(
                (f - f64::from(wi / total)).abs() < tolerance(trials),
                "{f} vs {}",
                wi / total
            );
        }
    }

    #[test]
    fn two_draws_match_exact_enumeration() {
        let w = [1.0f64, 2.0, 3.0, 6.0];
        let total: f64 = w.iter().sum();
        // P(i in S) = Σ over ordered pairs (a, b), a ≠ b, containing i of w_a/W · w_b/(W − w_a).
        let mut exact = [0.0f64; 4];
        for a in 0..4 {
            for b in 0..4 {
                if a != b {
                    let p = w[a] / total * w[b] / (total - w[a]);
                    exact[a] += p;
                    exact[b] += p;
                }
            }
        }
        assert!((exact.iter().sum::<f64>() - 2.0).abs() < 1e-12);
        let trials = 20_000;
        let wf: Vec<f32> = w.iter().map(|&x| x as f32).collect();
        for (f, e) in frequencies(&wf, 2, trials).iter().zip(exact) {
            assert!((f - e).abs() < tolerance(trials), "{f} vs {e}");
        }
    }

    #[test]
    fn uniform_inclusion_is_k_over_n_and_draws_are_distinct() {
        let trials = 5000;
        let mut count = [0usize; 10];
        for seed in 0..trials {
            let s = uniform_sampling(10, 3, seed).unwrap();
            let mut sorted = s.clone();
            sorted.sort_unstable();
            sorted.dedup();
            assert_eq!(sorted.len(), 3);
            for i in s {
                count[i as usize] += 1;
            }
        }
        for c in count {
            assert!((c as f64 / trials as f64 - 0.3).abs() < tolerance(trials));
        }
    }

    #[test]
    fn zero_weights_come_last_and_uniformly() {
        let w = [0.0f32, 1.0, 0.0, 2.0, 0.0];
        let trials = 6000;
        let mut third = [0usize; 5];
        for seed in 0..trials {
            let s = weighted_sampling(&w, 3, seed).unwrap();
            let mut first_two = [s[0], s[1]];
            first_two.sort_unstable();
            assert_eq!(first_two, [1, 3]);
            third[s[2] as usize] += 1;
        }
        for i in [0, 2, 4] {
            assert!((third[i] as f64 / trials as f64 - 1.0 / 3.0).abs() < tolerance(trials));
        }
    }

    #[test]
    fn independent_of_thread_count() {
        let w: Vec<f32> = (0..100_000)
            .map(|i| ((i * 7919) % 1000) as f32 / 1000.0)
            .collect();
        let run = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| weighted_sampling(&w, 5000, 11).unwrap())
        };
        assert_eq!(run(1), run(2));
        assert_ne!(run(1), weighted_sampling(&w, 5000, 12).unwrap());
    }

    proptest::proptest! {
        #[test]
        fn draws_are_distinct_prefix_stable_and_skip_zeros_while_positives_remain(
            weights in proptest::collection::vec(0.0f32..5.0, 1..200),
            frac in 0.0f64..=1.0,
            seed in 0u64..1000,
        ) {
            let k = (weights.len() as f64 * frac) as usize;
            let s = weighted_sampling(&weights, k, seed).unwrap();
            let mut sorted = s.clone();
            sorted.sort_unstable();
            sorted.dedup();
            proptest::prop_assert_eq!(sorted.len(), k);
            let positive = weights.iter().filter(|&&w| w > 0.0).count();
            for (rank, &i) in s.iter().enumerate() {
                proptest::prop_assert_eq!(weights[i as usize] > 0.0, rank < positive);
            }
            // A smaller sample with the same seed is a prefix of the larger one.
            let half = weighted_sampling(&weights, k / 2, seed).unwrap();
            proptest::prop_assert_eq!(&s[..k / 2], half.as_slice());
        }
    }

    #[test]
    fn rejects_invalid_weights_and_k() {
        assert!(matches!(
            weighted_sampling(&[1.0, -0.5], 1, 0),
            Err(Error::InvalidWeight { index: 1, .. })
        ));
        assert!(weighted_sampling(&[1.0, f32::NAN], 1, 0).is_err());
        assert!(weighted_sampling(&[1.0, f32::INFINITY], 1, 0).is_err());
        assert!(weighted_sampling(&[1.0], 2, 0).is_err());
        assert_eq!(weighted_sampling(&[], 0, 0).unwrap(), Vec::<u32>::new());
    }
}
