//! Systematic probability-proportional-to-size sampling of a sequence: the weights laid end to
//! end, `k` positions taken at the equally spaced points `(u + j)·W/k` (one uniform `u` from
//! the seed, `W` the total weight). Each item is included with probability `k·w_i/W` (capped
//! at 1), and neighbours in the sequence are rarely both taken. Along a space-filling curve
//! this is [`crate::balanced_sampling`]; a caller that already holds its items in curve order
//! (the point sampler lays its points out along the curve) draws on them directly.
//!
//! # Conventions
//! - An item whose weight spans several points is taken once; the extra points take the next
//!   items not yet taken, so the result always has `k` distinct positions.
//! - The drawn positions come in sequence order; zero weights are taken only when the
//!   positive weights cannot fill `k` (or rounding leaves the last point off the end): then
//!   the first free positions follow, again in sequence order.

use rand::{Rng, SeedableRng, rngs::StdRng};

use crate::{Error, Result};

/// `k` distinct positions in `0..weights.len()` drawn by `weights` (module docs), seeded.
///
/// Errors when `k` exceeds the number of weights or a weight is negative or not finite.
///
/// ```
/// use meshgnn_graph::systematic_sampling;
/// // Equal weights: one pick in every run of 4, at the same offset.
/// let picked = systematic_sampling(&[1.0; 12], 3, 5)?;
/// assert_eq!(picked.len(), 3);
/// assert!(picked.windows(2).all(|w| w[1] - w[0] == 4));
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn systematic_sampling(weights: &[f32], k: usize, seed: u64) -> Result<Vec<u32>> {
    let n = weights.len();
    if k > n {
        return Err(Error::InvalidParameter {
            name: "k",
            message: format!("cannot draw {k} distinct items out of {n}"),
        });
    }
    if let Some((index, &value)) = weights
        .iter()
        .enumerate()
        .find(|(_, w)| !(w.is_finite() && **w >= 0.0))
    {
        return Err(Error::InvalidWeight { index, value });
    }
    if k == 0 {
        return Ok(Vec::new());
    }
    let total: f64 = weights.iter().map(|&w| f64::from(w)).sum();
    let mut taken = vec![false; n];
    let mut picked = Vec::with_capacity(k);
    if total > 0.0 {
        let step = total / k as f64;
        let mut next = StdRng::seed_from_u64(seed).random::<f64>() * step;
        let mut cumulative = 0.0;
        // `cursor` is the first position that may still be free.
        let mut cursor = 0;
        for (position, &w) in weights.iter().enumerate() {
            cumulative += f64::from(w);
            while next < cumulative && picked.len() < k {
                if taken[position] {
                    cursor = cursor.max(position);
                    while cursor < n && taken[cursor] {
                        cursor += 1;
                    }
                    if cursor == n {
                        break;
                    }
                    taken[cursor] = true;
                    picked.push(cursor as u32);
                } else {
                    taken[position] = true;
                    picked.push(position as u32);
                }
                next += step;
            }
        }
    }
    // Rounding at the end, or too few positive weights: fill in sequence order.
    for (position, taken) in taken.iter_mut().enumerate() {
        if picked.len() == k {
            break;
        }
        if !*taken {
            *taken = true;
            picked.push(position as u32);
        }
    }
    Ok(picked)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inclusion_follows_the_weights() {
        // Weights 3 on the first half, 1 on the second: three picks in four on the first.
        let weights: Vec<f32> = (0..400).map(|i| if i < 200 { 3.0 } else { 1.0 }).collect();
        let picked = systematic_sampling(&weights, 40, 9).unwrap();
        assert_eq!(picked.iter().filter(|&&i| i < 200).count(), 30);
        assert!(picked.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(systematic_sampling(&weights, 40, 9).unwrap(), picked);
        assert_ne!(systematic_sampling(&weights, 40, 10).unwrap(), picked);
    }

    #[test]
    fn a_heavy_item_is_taken_once_and_the_next_free_ones_fill_in() {
        // All the weight on item 4 and 6 picks: 4, then the free items after it, then the
        // rest from the start.
        let mut weights = [0.0f32; 10];
        weights[4] = 5.0;
        assert_eq!(
            systematic_sampling(&weights, 6, 1).unwrap(),
            [4, 5, 6, 7, 8, 9]
        );
        assert_eq!(
            systematic_sampling(&weights, 8, 1).unwrap(),
            [4, 5, 6, 7, 8, 9, 0, 1]
        );
        assert_eq!(systematic_sampling(&[0.0; 10], 3, 1).unwrap(), [0, 1, 2]);
        assert_eq!(systematic_sampling(&[1.0; 10], 10, 1).unwrap().len(), 10);
    }

    proptest::proptest! {
        #[test]
        fn k_distinct_positions_and_every_item_worth_a_whole_step_taken(
            weights in proptest::collection::vec(0.0f32..5.0, 1..300),
            frac in 0.0f64..=1.0,
            seed in 0u64..1000,
        ) {
            let k = (weights.len() as f64 * frac) as usize;
            let picked = systematic_sampling(&weights, k, seed).unwrap();
            let mut distinct = picked.clone();
            distinct.sort_unstable();
            distinct.dedup();
            proptest::prop_assert_eq!(distinct.len(), k);
            proptest::prop_assert!(picked.iter().all(|&p| (p as usize) < weights.len()));
            // An item whose weight spans a whole step holds one of the equally spaced points.
            let total: f64 = weights.iter().map(|&w| f64::from(w)).sum();
            for (i, &w) in weights.iter().enumerate() {
                if k > 0 && f64::from(w) * k as f64 >= total * (1.0 + 1e-9) {
                    proptest::prop_assert!(picked.contains(&(i as u32)), "item {} ({})", i, w);
                }
            }
            proptest::prop_assert_eq!(systematic_sampling(&weights, k, seed).unwrap(), picked);
        }
    }

    #[test]
    fn bad_input_is_an_error() {
        assert!(systematic_sampling(&[1.0; 3], 4, 0).is_err());
        assert!(systematic_sampling(&[1.0, -1.0, 1.0], 1, 0).is_err());
        assert!(systematic_sampling(&[1.0, f32::NAN], 1, 0).is_err());
        assert!(systematic_sampling(&[], 0, 0).unwrap().is_empty());
    }
}
