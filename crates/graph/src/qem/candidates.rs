//! The sorted candidate list of a QEM decimation pass (Garland & Heckbert, SIGGRAPH 1997:
//! "iteratively remove the pair of least cost"; thesis ch. 2.3.2): edges keyed by a
//! monotone 32-bit image of their cost, ordered by a stable LSD radix sort instead of a
//! comparison sort (sorting was the largest instruction count of the decimation).
//!
//! # Conventions
//! The key keeps the top 32 bits of the cost's `f64` bit pattern (sign, exponent and 20
//! mantissa bits): for the non-negative costs of quadrics it is monotone in the cost and
//! resolves relative differences of about 1e-6. Ties keep their input order (the sort is
//! stable), which is deterministic, so the order is the same for any thread count.

/// An edge `(a, b)` with its cost key.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Candidate {
    pub key: u32,
    pub a: u32,
    pub b: u32,
}

/// The monotone 32-bit key of a non-negative cost (negative or NaN costs map to 0 and
/// `u32::MAX`; quadric costs are neither).
pub(crate) fn cost_key(cost: f64) -> u32 {
    if cost.is_nan() {
        u32::MAX
    } else if cost <= 0.0 {
        0
    } else {
        (cost.to_bits() >> 32) as u32
    }
}

/// The smallest cost with key `key` (the inverse of [`cost_key`] up to its resolution).
pub(crate) fn key_cost(key: u32) -> f64 {
    f64::from_bits(u64::from(key) << 32)
}

/// Sorts `items` by `key` with a stable LSD radix sort (three 11-bit digits). O(n). The second
/// buffer lives only for the call: kept between calls at the size of the first, largest
/// sort, it raised the decimation's peak memory by 16 MB on a 1.3M-face mesh.
pub(crate) fn radix_sort(items: &mut Vec<Candidate>) {
    const BITS: u32 = 11;
    const BUCKETS: usize = 1 << BITS;
    let n = items.len();
    if n < 2 {
        return;
    }
    // All three histograms in one read.
    let mut counts = vec![[0usize; BUCKETS]; 3];
    for c in items.iter() {
        for (d, count) in counts.iter_mut().enumerate() {
            count[(c.key >> (BITS * d as u32)) as usize & (BUCKETS - 1)] += 1;
        }
    }
    let mut scratch = vec![Candidate { key: 0, a: 0, b: 0 }; n];
    for (d, count) in counts.iter_mut().enumerate() {
        // A digit shared by every item leaves the order as it is.
        if count.contains(&n) {
            continue;
        }
        let mut offset = 0;
        for c in count.iter_mut() {
            let here = *c;
            *c = offset;
            offset += here;
        }
        let shift = BITS * d as u32;
        for item in items.iter() {
            let bucket = (item.key >> shift) as usize & (BUCKETS - 1);
            scratch[count[bucket]] = *item;
            count[bucket] += 1;
        }
        std::mem::swap(items, &mut scratch);
    }
}

/// Merges the items of `first` that pass `keep` with `second` (both key-sorted); on equal
/// keys `first`'s items come first. Filtering while merging reads `first` once.
pub(crate) fn merge_sorted(
    first: &[Candidate],
    keep: impl Fn(&Candidate) -> bool,
    second: &[Candidate],
) -> Vec<Candidate> {
    let mut merged = Vec::with_capacity(first.len() + second.len());
    let mut j = 0;
    for item in first.iter().filter(|c| keep(c)) {
        while let Some(next) = second.get(j).filter(|n| n.key < item.key) {
            merged.push(*next);
            j += 1;
        }
        merged.push(*item);
    }
    merged.extend_from_slice(second.get(j..).unwrap_or_default());
    merged
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn key_is_monotone_and_inverts_to_a_lower_bound() {
        let costs = [0.0, 1e-300, 1e-12, 0.5, 0.5000001, 1.0, 3.0, 1e12];
        for w in costs.windows(2) {
            assert!(cost_key(w[0]) <= cost_key(w[1]));
        }
        for &c in &costs {
            let back = key_cost(cost_key(c));
            assert!(back <= c && c - back <= 1e-6 * c, "{c} {back}");
        }
        assert!(cost_key(0.5) < cost_key(0.5001));
    }

    #[test]
    fn radix_sort_matches_a_stable_comparison_sort() {
        // Pseudo-random keys with many ties in the low digits and across digits.
        let mut items: Vec<Candidate> = (0..5000u32)
            .map(|i| Candidate {
                key: (i.wrapping_mul(2_654_435_761) >> 7) & 0x3fff_f00f,
                a: i,
                b: i + 1,
            })
            .collect();
        let mut expected = items.clone();
        expected.sort_by_key(|c| c.key);
        radix_sort(&mut items);
        assert_eq!(items, expected);
    }

    #[test]
    fn merge_prefers_the_first_list_on_ties() {
        let c = |key, a| Candidate { key, a, b: 0 };
        let merged = merge_sorted(&[c(1, 0), c(3, 1)], |_| true, &[c(1, 2), c(2, 3), c(4, 4)]);
        let order: Vec<u32> = merged.iter().map(|x| x.a).collect();
        assert_eq!(order, vec![0, 2, 3, 1, 4]);
        // Filtered items of the first list are dropped, the second list kept whole.
        let first = [c(1, 0), c(2, 1), c(5, 2), c(6, 3)];
        let merged = merge_sorted(&first, |x| x.a % 2 == 0, &[c(2, 4), c(7, 5)]);
        let order: Vec<u32> = merged.iter().map(|x| x.a).collect();
        assert_eq!(order, vec![0, 4, 2, 5]);
    }
}
