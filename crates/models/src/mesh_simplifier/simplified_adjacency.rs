//! Eq. 6.3-6.4, `A_s[a, b] = Σ_i Σ_{j ∈ N(i) ∪ {i}} Ŝ[i, a] Ŝ[j, b]` (with `A = A_ext + I`),
//! as one fused operation over the attention weights, on the pairs
//! [`super::ExtendedGraph`] evaluates it on. Listing the product's terms first costs one
//! entry per term: 107M terms (1.7 GB while sorted, 1.3 GB kept) and 6 s to list them for an
//! 872k-face mesh at a tenth of its vertices; the structure they come from — which attention
//! entries hold each sampled vertex, the rows, the sampled entries of each row — is a few
//! entries per vertex, and the terms are walked from it in every pass instead.
//!
//! Every pair's terms are added in the order `(p, q)` of their two attention entries (the
//! order a sorted term list gives), so the values do not depend on the thread count.
//!
//! The backward pass gives each attention entry `p = Ŝ[i, a]` the sum over the terms it is the
//! left factor of, `(g[a, b] + g[b, a]) Ŝ[j, b]`: the term `(b, a)` whose right factor is `p`
//! is the mirror of the term `(a, b)` whose left factor it is (the rows are symmetric), so one
//! task per sampled vertex owns every entry it writes.

use std::ops::Range;
use std::sync::Arc;

use candle_core::{CpuStorage, CustomOp1, Layout, Shape, Tensor};
use rayon::prelude::*;

use super::flat_rows::FlatRows;
use super::op_operands::{Real, contiguous, host_f64};

/// The name in error messages.
const NAME: &str = "simplified adjacency";

/// Sampled vertices per parallel task.
const SAMPLES_PER_TASK: usize = 64;

/// The structure of `A_s` over `N` points with `M` of them sampled: what the terms are walked
/// from.
#[derive(Debug)]
pub(super) struct SimplifiedAdjacencyPattern {
    /// Width `W` of the attention rows; an entry is `p = i·W + s`.
    width: usize,
    /// `N`.
    points: usize,
    /// Per sampled vertex `a`: the entries `p` whose slot holds `a`, increasing.
    columns: FlatRows<u32>,
    /// Per point `i`: `N(i) ∪ {i}`, increasing.
    neighbourhoods: FlatRows<u32>,
    /// Per point `j`: `(q, b)` for every slot of its attention row holding a sampled vertex
    /// `b`, `q` increasing.
    sampled_entries: FlatRows<(u32, u32)>,
    /// Per sampled vertex `a`: the pairs `(a, b)` evaluated, `b` increasing; the pair's index
    /// is its position in this flat list.
    linked: FlatRows<u32>,
    /// Per pair `(a, b)`: the index of `(b, a)`.
    transposed: Vec<u32>,
}

impl SimplifiedAdjacencyPattern {
    /// The pattern for symmetric `rows` (`N(i)`, increasing, without `i`), attention rows
    /// `[i, N(i)…]` of `width` slots, `sample_position[i]` (`u32::MAX` when `i` is not sampled)
    /// and the `linked` sampled vertices of every sampled vertex (increasing, symmetric).
    pub(super) fn new(
        rows: &[Vec<u32>],
        width: usize,
        sample_position: &[u32],
        linked: &[Vec<u32>],
    ) -> Result<Self, String> {
        let sampled_entries = FlatRows::new(rows.iter().enumerate().map(|(i, row)| {
            std::iter::once(i as u32)
                .chain(row.iter().copied())
                .enumerate()
                .filter_map(move |(s, j)| {
                    let b = sample_position[j as usize];
                    (b != u32::MAX).then_some(((i * width + s) as u32, b))
                })
        }));
        let mut columns = vec![Vec::new(); linked.len()];
        for &(p, a) in &sampled_entries.items {
            columns[a as usize].push(p);
        }
        let neighbourhoods = FlatRows::new(rows.iter().enumerate().map(|(i, row)| {
            let i = i as u32;
            let split = row.partition_point(|&j| j < i);
            row[..split]
                .iter()
                .copied()
                .chain(std::iter::once(i))
                .chain(row[split..].iter().copied())
        }));
        let linked = FlatRows::new(linked.iter().map(|row| row.iter().copied()));
        let transposed = (0..linked.len())
            .flat_map(|a| linked.of(a).iter().map(move |&b| (a as u32, b)))
            .map(|(a, b)| {
                let start = linked.starts[b as usize];
                linked
                    .of(b as usize)
                    .binary_search(&a)
                    .map(|rank| (start + rank) as u32)
                    .map_err(|_| format!("sampled vertex {b} is linked to {a} but not back"))
            })
            .collect::<Result<_, _>>()?;
        Ok(Self {
            width,
            points: rows.len(),
            columns: FlatRows::new(columns),
            neighbourhoods,
            sampled_entries,
            linked,
            transposed,
        })
    }

    /// The number of pairs evaluated.
    pub(super) fn pair_count(&self) -> usize {
        self.linked.items.len()
    }

    /// Calls `term(k, r, q)` for every term `Ŝ[i, a] Ŝ[j, b]` of sampled vertex `a`, with `p`
    /// the `k`-th entry of column `a`, `r` the rank of `b` among `a`'s linked vertices and `q`
    /// the entry of `Ŝ[j, b]`, in `(p, q)` order; `rank[b]` holds that rank (or `u32::MAX`).
    fn for_each_term(&self, a: usize, rank: &[u32], mut term: impl FnMut(usize, usize, usize)) {
        for (k, &p) in self.columns.of(a).iter().enumerate() {
            let i = p as usize / self.width;
            for &j in self.neighbourhoods.of(i) {
                for &(q, b) in self.sampled_entries.of(j as usize) {
                    let r = rank[b as usize];
                    if r != u32::MAX {
                        term(k, r as usize, q as usize);
                    }
                }
            }
        }
    }

    /// Runs `task(a, rank)` for every sampled vertex in `range`, with `rank` set for `a`'s
    /// linked vertices (`scratch`: `M` entries of `u32::MAX`, left so).
    fn with_ranks(
        &self,
        range: Range<usize>,
        scratch: &mut [u32],
        mut task: impl FnMut(usize, &[u32]),
    ) {
        for a in range {
            let linked = self.linked.of(a);
            for (r, &b) in linked.iter().enumerate() {
                scratch[b as usize] = r as u32;
            }
            task(a, scratch);
            for &b in linked {
                scratch[b as usize] = u32::MAX;
            }
        }
    }

    /// The sampled-vertex ranges of the parallel tasks.
    fn task_ranges(&self) -> Vec<Range<usize>> {
        let m = self.linked.len();
        (0..m.div_ceil(SAMPLES_PER_TASK))
            .map(|t| t * SAMPLES_PER_TASK..((t + 1) * SAMPLES_PER_TASK).min(m))
            .collect()
    }

    fn check(&self, shape: &Shape) -> candle_core::Result<()> {
        if shape.dims2()? != (self.points, self.width) {
            candle_core::bail!(
                "{NAME}: attention {shape:?} for {} points of {} slots",
                self.points,
                self.width
            );
        }
        Ok(())
    }

    fn forward<T: Real>(&self, attention: &[T]) -> Vec<T> {
        let mut values = vec![T::ZERO; self.pair_count()];
        let ranges = self.task_ranges();
        let mut slices = Vec::with_capacity(ranges.len());
        let mut rest = values.as_mut_slice();
        for range in &ranges {
            let count = self.linked.starts[range.end] - self.linked.starts[range.start];
            let (head, tail) = rest.split_at_mut(count);
            slices.push(head);
            rest = tail;
        }
        let m = self.linked.len();
        ranges.into_par_iter().zip(slices).for_each_init(
            || vec![u32::MAX; m],
            |scratch, (range, out)| {
                let base = self.linked.starts[range.start];
                self.with_ranks(range, scratch, |a, rank| {
                    let start = self.linked.starts[a] - base;
                    let sums = &mut out[start..start + self.linked.of(a).len()];
                    let column = self.columns.of(a);
                    self.for_each_term(a, rank, |k, r, q| {
                        sums[r] += attention[column[k] as usize] * attention[q];
                    });
                });
            },
        );
        values
    }

    /// The gradient of the attention entries from `grad` on the pairs (module docs).
    fn backward(&self, attention: &[f64], grad: &[f64]) -> Vec<f64> {
        let m = self.linked.len();
        let per_column: Vec<Vec<f64>> = self
            .task_ranges()
            .into_par_iter()
            .map_init(
                || vec![u32::MAX; m],
                |scratch, range| {
                    let mut sums = Vec::new();
                    self.with_ranks(range, scratch, |a, rank| {
                        let mut column = vec![0.0; self.columns.of(a).len()];
                        let first_pair = self.linked.starts[a];
                        self.for_each_term(a, rank, |k, r, q| {
                            let pair = first_pair + r;
                            let both = grad[pair] + grad[self.transposed[pair] as usize];
                            column[k] += both * attention[q];
                        });
                        sums.push(column);
                    });
                    sums
                },
            )
            .flatten()
            .collect();
        let mut out = vec![0.0; attention.len()];
        for (a, sums) in per_column.iter().enumerate() {
            for (&p, &g) in self.columns.of(a).iter().zip(sums) {
                out[p as usize] = g;
            }
        }
        out
    }
}

/// `A_s` on the pattern's pairs from `attention: (N, W)`; gradients reach `attention`.
pub(super) fn simplified_adjacency(
    attention: &Tensor,
    pattern: &Arc<SimplifiedAdjacencyPattern>,
) -> candle_core::Result<Tensor> {
    attention.contiguous()?.apply_op1(SimplifiedAdjacency {
        pattern: Arc::clone(pattern),
    })
}

struct SimplifiedAdjacency {
    pattern: Arc<SimplifiedAdjacencyPattern>,
}

impl CustomOp1 for SimplifiedAdjacency {
    fn name(&self) -> &'static str {
        "simplified-adjacency"
    }

    fn cpu_fwd(
        &self,
        storage: &CpuStorage,
        layout: &Layout,
    ) -> candle_core::Result<(CpuStorage, Shape)> {
        self.pattern.check(layout.shape())?;
        let out = match storage {
            CpuStorage::F32(a) => {
                CpuStorage::F32(self.pattern.forward(contiguous(a, layout, NAME)?))
            }
            CpuStorage::F64(a) => {
                CpuStorage::F64(self.pattern.forward(contiguous(a, layout, NAME)?))
            }
            _ => candle_core::bail!("{NAME}: attention must be f32 or f64"),
        };
        Ok((out, Shape::from(self.pattern.pair_count())))
    }

    fn bwd(
        &self,
        attention: &Tensor,
        _result: &Tensor,
        grad: &Tensor,
    ) -> candle_core::Result<Option<Tensor>> {
        self.pattern.check(attention.shape())?;
        let values = self
            .pattern
            .backward(&host_f64(attention)?, &host_f64(grad)?);
        Ok(Some(
            Tensor::from_vec(values, attention.shape(), attention.device())?
                .to_dtype(attention.dtype())?,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::{DType, Device};
    use meshgnn_losses::losses::gradient_disagreement;

    /// Five points on a path 0-1-2-3-4 plus the link 0-4, points 0, 2 and 4 sampled, with
    /// every sampled pair linked.
    fn pattern() -> (Arc<SimplifiedAdjacencyPattern>, Vec<Vec<u32>>, Vec<u32>) {
        let rows = vec![vec![1, 4], vec![0, 2], vec![1, 3], vec![2, 4], vec![0, 3]];
        let sampled = vec![0, 2, 4];
        let mut position = vec![u32::MAX; 5];
        for (a, &i) in sampled.iter().enumerate() {
            position[i as usize] = a as u32;
        }
        let linked = vec![vec![1, 2], vec![0, 2], vec![0, 1]];
        let pattern = SimplifiedAdjacencyPattern::new(&rows, 3, &position, &linked).unwrap();
        (Arc::new(pattern), rows, sampled)
    }

    /// Attention weights on the real slots of `[i, N(i)…]`, 0 elsewhere.
    fn attention(rows: &[Vec<u32>]) -> Tensor {
        let values: Vec<f64> = (0..rows.len() * 3)
            .map(|e| {
                if e % 3 <= rows[e / 3].len() {
                    0.1 + 0.07 * e as f64
                } else {
                    0.0
                }
            })
            .collect();
        Tensor::from_vec(values, (rows.len(), 3), &Device::Cpu).unwrap()
    }

    #[test]
    fn equals_the_dense_product_on_the_linked_pairs() {
        let (pattern, rows, sampled) = pattern();
        let weights: Vec<Vec<f64>> = attention(&rows).to_vec2().unwrap();
        // Dense Ŝ (N × M) and A + I.
        let n = rows.len();
        let mut s_hat = vec![vec![0.0; sampled.len()]; n];
        for (i, row) in rows.iter().enumerate() {
            for (s, &j) in std::iter::once(&(i as u32)).chain(row).enumerate() {
                if let Some(a) = sampled.iter().position(|&x| x == j) {
                    s_hat[i][a] = weights[i][s];
                }
            }
        }
        let adjacent = |i: usize, j: usize| i == j || rows[i].contains(&(j as u32));
        let dense = |a: usize, b: usize| -> f64 {
            let mut total = 0.0;
            for i in 0..n {
                for j in 0..n {
                    if adjacent(i, j) {
                        total += s_hat[i][a] * s_hat[j][b];
                    }
                }
            }
            total
        };
        let got: Vec<f64> = simplified_adjacency(&attention(&rows), &pattern)
            .unwrap()
            .to_vec1()
            .unwrap();
        let pairs = [(0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1)];
        assert_eq!(got.len(), pairs.len());
        for (value, (a, b)) in got.iter().zip(pairs) {
            assert!((value - dense(a, b)).abs() <= 1e-12, "({a}, {b})");
            assert!(*value > 0.0);
        }
        let single =
            simplified_adjacency(&attention(&rows).to_dtype(DType::F32).unwrap(), &pattern)
                .unwrap()
                .to_vec1::<f32>()
                .unwrap();
        for (a, b) in single.iter().zip(&got) {
            assert!((f64::from(*a) - b).abs() <= 1e-6);
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]

        /// Any symmetric graph, any sample, any attention: the dense product on the linked
        /// pairs, and finite-difference gradients.
        #[test]
        fn any_graph_gives_the_dense_product_and_its_gradient(
            n in 2usize..10,
            edges in proptest::collection::vec(proptest::bool::weighted(0.35), 45),
            sampled in proptest::collection::vec(proptest::bool::ANY, 10),
            weights in proptest::collection::vec(0.05f64..1.0, 100),
        ) {
            let mut rows = vec![Vec::new(); n];
            let mut e = 0;
            for i in 0..n {
                for j in i + 1..n {
                    if edges[e] {
                        rows[i].push(j as u32);
                        rows[j].push(i as u32);
                    }
                    e += 1;
                }
            }
            let picked: Vec<usize> = (0..n).filter(|&i| sampled[i]).collect();
            proptest::prop_assume!(!picked.is_empty());
            let mut position = vec![u32::MAX; n];
            for (a, &i) in picked.iter().enumerate() {
                position[i] = a as u32;
            }
            let linked: Vec<Vec<u32>> = picked
                .iter()
                .map(|&i| {
                    let mut l: Vec<u32> = rows[i]
                        .iter()
                        .map(|&j| position[j as usize])
                        .filter(|&b| b != u32::MAX)
                        .collect();
                    l.sort_unstable();
                    l
                })
                .collect();
            let width = rows.iter().map(Vec::len).max().unwrap_or(0) + 1;
            let pattern =
                Arc::new(SimplifiedAdjacencyPattern::new(&rows, width, &position, &linked).unwrap());
            // Attention on the real slots `[i, N(i)…]`, 0 on the padding.
            let values: Vec<f64> = (0..n * width)
                .map(|p| if p % width <= rows[p / width].len() { weights[p] } else { 0.0 })
                .collect();
            let attention = Tensor::from_vec(values.clone(), (n, width), &Device::Cpu).unwrap();
            let s_hat = |i: usize, a: usize| -> f64 {
                std::iter::once(i as u32)
                    .chain(rows[i].iter().copied())
                    .position(|j| j as usize == picked[a])
                    .map_or(0.0, |s| values[i * width + s])
            };
            let got: Vec<f64> =
                simplified_adjacency(&attention, &pattern).unwrap().to_vec1().unwrap();
            let mut pair = 0;
            for (a, row) in linked.iter().enumerate() {
                for &b in row {
                    let mut dense = 0.0;
                    for (i, row) in rows.iter().enumerate() {
                        for j in std::iter::once(i as u32).chain(row.iter().copied()) {
                            dense += s_hat(i, a) * s_hat(j as usize, b as usize);
                        }
                    }
                    proptest::prop_assert!((got[pair] - dense).abs() <= 1e-12);
                    pair += 1;
                }
            }
            proptest::prop_assert_eq!(pair, got.len());
            if !got.is_empty() {
                let scale: Vec<f64> = (0..got.len()).map(|k| 1.0 + k as f64 * 0.37).collect();
                let scale = Tensor::from_vec(scale, got.len(), &Device::Cpu).unwrap();
                let worst = gradient_disagreement(&attention, |x| {
                    (simplified_adjacency(x, &pattern)? * &scale)?.sum_all()
                })
                .unwrap();
                proptest::prop_assert!(worst.relative_error <= 1e-6, "{:?}", worst);
            }
        }
    }

    #[test]
    fn gradients_match_finite_differences() {
        let (pattern, rows, _) = pattern();
        let scale = Tensor::new(&[1.0f64, -2.0, 3.0, 0.5, -1.5, 2.5], &Device::Cpu).unwrap();
        let worst = gradient_disagreement(&attention(&rows), |x| {
            (simplified_adjacency(x, &pattern)? * &scale)?.sum_all()
        })
        .unwrap();
        assert!(worst.relative_error <= 1e-6, "{worst:?}");
        assert!(worst.largest_gradient > 0.1, "{worst:?}");
    }

    #[test]
    fn mismatched_operands_are_errors() {
        let (pattern, rows, _) = pattern();
        let narrow = attention(&rows).narrow(1, 0, 2).unwrap();
        assert!(simplified_adjacency(&narrow, &pattern).is_err());
        let position = [0, u32::MAX, 1, u32::MAX, 2];
        let one_way = vec![vec![1, 2], vec![2], vec![0, 1]];
        assert!(SimplifiedAdjacencyPattern::new(&rows, 3, &position, &one_way).is_err());
    }
}
