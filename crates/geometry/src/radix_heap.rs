//! A monotone priority queue for the multi-source Dijkstra of the geodesic partition: a radix
//! heap (Ahuja, Mehlhorn, Orlin & Tarjan, "Faster algorithms for the shortest path problem",
//! J. ACM 1990) over `(distance bits, seed)` keys. Dijkstra never pushes a key below the one
//! it last popped, so an entry is filed by the highest bit in which its key differs from the
//! last popped key and each entry moves down the buckets at most once per bit: a pop touches
//! a few cache lines where a binary heap of 100k entries walks 17 levels.
//!
//! Keys pop in increasing `(distance bits, seed)` order (non-negative `f64`s order as their
//! bit patterns); entries of equal key pop in no particular order.

/// Buckets: one for keys equal to the last popped, then one per differing bit of the seed
/// (32) and of the distance (64).
const BUCKETS: usize = 1 + 32 + 64;

/// One queued vertex: its key `(distance bits, seed)` and the vertex.
type Entry = (u64, u32, u32);

/// Entries filed by their key's highest bit of difference from the last popped key.
pub(crate) struct RadixHeap {
    buckets: Vec<Vec<Entry>>,
    last: (u64, u32),
}

impl RadixHeap {
    /// An empty queue whose first key may be any.
    pub(crate) fn new() -> Self {
        Self {
            buckets: vec![Vec::new(); BUCKETS],
            last: (0, 0),
        }
    }

    /// Queues `vertex` under `(distance_bits, seed)`, which must not be below the last popped
    /// key (a Dijkstra's relaxations never are).
    pub(crate) fn push(&mut self, distance_bits: u64, seed: u32, vertex: u32) {
        debug_assert!(
            (distance_bits, seed) >= self.last,
            "key below the last popped"
        );
        let bucket = self.bucket_of(distance_bits, seed);
        self.buckets[bucket].push((distance_bits, seed, vertex));
    }

    /// An entry of the least key, or `None` when empty.
    pub(crate) fn pop(&mut self) -> Option<Entry> {
        if self.buckets[0].is_empty() {
            let bucket = self.buckets.iter().position(|b| !b.is_empty())?;
            let mut spilled = std::mem::take(&mut self.buckets[bucket]);
            let &(bits, seed, _) = spilled.iter().min()?;
            self.last = (bits, seed);
            // Every spilled entry now differs from the last key in a lower bit than before.
            for &(bits, seed, vertex) in &spilled {
                let lower = self.bucket_of(bits, seed);
                self.buckets[lower].push((bits, seed, vertex));
            }
            spilled.clear();
            self.buckets[bucket] = spilled;
        }
        self.buckets[0].pop()
    }

    /// 0 for the last popped key, else one past the highest differing bit (the seed's bits
    /// below the distance's).
    fn bucket_of(&self, distance_bits: u64, seed: u32) -> usize {
        let (last_bits, last_seed) = self.last;
        if distance_bits != last_bits {
            33 + (63 - (distance_bits ^ last_bits).leading_zeros() as usize)
        } else if seed != last_seed {
            1 + (31 - (seed ^ last_seed).leading_zeros() as usize)
        } else {
            0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;

    #[test]
    fn pops_in_key_order_with_equal_keys_together() {
        let mut heap = RadixHeap::new();
        for (bits, seed, vertex) in [(5, 2, 0), (5, 1, 1), (0, 7, 2), (1 << 40, 0, 3), (5, 1, 4)] {
            heap.push(bits, seed, vertex);
        }
        let keys: Vec<(u64, u32)> = std::iter::from_fn(|| heap.pop())
            .map(|(b, s, _)| (b, s))
            .collect();
        assert_eq!(keys, [(0, 7), (5, 1), (5, 1), (5, 2), (1 << 40, 0)]);
    }

    proptest! {
        /// A Dijkstra-like run (every push at or above the last pop) pops the keys a binary
        /// heap pops, in the same order.
        #[test]
        fn pops_what_a_binary_heap_pops(
            steps in proptest::collection::vec((0u64..1 << 50, 0u32..40, 0usize..4), 1..300)
        ) {
            let mut radix = RadixHeap::new();
            let mut binary = BinaryHeap::new();
            let mut last = (0u64, 0u32);
            for (i, &(step, seed, pops)) in steps.iter().enumerate() {
                // Keys at or above the last popped: a distance step, or the same distance
                // with a seed no lower.
                let key = if step % 3 == 0 {
                    (last.0, last.1.max(seed))
                } else {
                    (last.0 + step, seed)
                };
                radix.push(key.0, key.1, i as u32);
                binary.push(Reverse(key));
                for _ in 0..pops {
                    let expected = binary.pop().map(|Reverse(k)| k);
                    let popped = radix.pop().map(|(b, s, _)| (b, s));
                    prop_assert_eq!(popped, expected);
                    if let Some(key) = popped {
                        last = key;
                    }
                }
            }
            while let Some(Reverse(key)) = binary.pop() {
                prop_assert_eq!(radix.pop().map(|(b, s, _)| (b, s)), Some(key));
            }
            prop_assert_eq!(radix.pop(), None);
        }
    }
}
