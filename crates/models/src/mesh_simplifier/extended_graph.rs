//! The graph the edge predictor works on (thesis ch. 6.3.2): the mesh adjacency extended by a
//! k-NN graph over the sampled vertices (k = 15, ch. 6.4) so that no sampled vertex is
//! isolated and, beyond the thesis, by the edges of the sampled vertices' nearest-seed dual (so
//! that every dual triangle can become a candidate: with the k-NN alone 1-3% of them had an
//! edge outside the graph on the test families), and the sparsity pattern of `A_s = Ŝᵀ A Ŝ`
//! (eq. 6.3-6.4) with the structure its terms are walked from in every pass
//! ([`super::simplified_adjacency`]).
//!
//! # Conventions
//! - `A` in eq. 6.4 is the *extended* adjacency with self-loops (`A_ext + I`): with the
//!   self-attention weight `S[i, i]` (each vertex attends to itself as well as to its
//!   neighbours), two sampled vertices that share an edge or a k-NN link are connected in `A_s`
//!   by the term `S[a, a] A[a, b] S[b, b]`. The thesis does not print the self-loops; without
//!   them a sampled vertex would have no weight on itself in `Ŝ`.
//! - Attention slots: row `i` lists `i` itself first, then its extended neighbours in
//!   increasing order, padded with the empty slot `N` ([`NeighbourSlots`]).
//! - `A` is undirected: an adjacency entry one way counts both ways.
//! - `A_s` is stored as its non-zero pattern `pairs` (`(a, b)` in sampled-vertex numbering,
//!   `a ≠ b`, sorted).
//! - Beyond the thesis, `A_s` is evaluated only on pairs of sampled vertices that are linked
//!   in the extended graph (a mesh edge, a k-NN link or a dual edge between them). The full product links
//!   two sampled vertices whenever some mesh edge joins two vertices attending to them: on
//!   icosphere(3) with 120 of 642 vertices sampled it filled 74% of all pairs (10 612) and gave
//!   120 050 candidate triangles for 120 vertices (measured), far beyond what a face classifier
//!   can score or a surface needs.

use std::sync::Arc;

use candle_core::{Device, Tensor};
use meshgnn_geometry::SpatialIndex;
use meshgnn_graph::CsrMatrix;
use rayon::prelude::*;

use super::NeighbourSlots;
use super::simplified_adjacency::{SimplifiedAdjacencyPattern, simplified_adjacency};
use crate::{Error, Result};

/// The extended graph over `N` vertices with `M` of them sampled, and the structure of the
/// eq. 6.4 product.
#[derive(Clone, Debug)]
pub struct ExtendedGraph {
    /// DevConv neighbourhoods: the extended adjacency without self-loops.
    pub(crate) conv_slots: NeighbourSlots,
    /// Attention neighbourhoods: self first, then the extended neighbours.
    pub(crate) attention_slots: NeighbourSlots,
    /// `(N, W)`: 0 on a real attention slot, a large negative number on an empty one.
    pub(crate) attention_mask: Tensor,
    /// Non-zero pattern of `A_s`, `(a, b)` sorted, `a ≠ b`.
    pairs: Vec<[u32; 2]>,
    /// What the terms of eq. 6.4 on `pairs` are walked from.
    pattern: Arc<SimplifiedAdjacencyPattern>,
    sampled: Vec<u32>,
    /// The dual's edges `(a, b)`, `a < b`, in sampled-vertex numbering: always candidates.
    dual_edges: Vec<(u32, u32)>,
}

/// Logit added to empty attention slots: its softmax weight underflows to exactly 0.
const EMPTY_SLOT_LOGIT: f32 = -1e30;

impl ExtendedGraph {
    /// The graph of `points: #N×3` with mesh `adjacency: #N×#N` (or an empty matrix for a
    /// point cloud) extended by the `k` nearest sampled vertices of every sampled vertex
    /// (`sampled`: distinct indices `< N`) and by the edges of `dual` (triangles in
    /// sampled-vertex numbering, [`meshgnn_geometry::nearest_seed_dual_triangles`]).
    pub fn new(
        points: &[[f32; 3]],
        adjacency: &CsrMatrix,
        sampled: &[u32],
        k: usize,
        dual: &[[u32; 3]],
        device: &Device,
    ) -> Result<Self> {
        let n = points.len();
        if adjacency.rows() != n || adjacency.cols() != n {
            return Err(Error::Invalid {
                what: "adjacency".into(),
                reason: format!("{}×{} for {n} points", adjacency.rows(), adjacency.cols()),
            });
        }
        let mut sample_position = vec![u32::MAX; n];
        for (a, &i) in sampled.iter().enumerate() {
            match sample_position.get_mut(i as usize) {
                Some(slot) if *slot == u32::MAX => *slot = a as u32,
                _ => {
                    return Err(Error::Invalid {
                        what: format!("sampled vertex {i}"),
                        reason: format!("repeated or out of range for {n} points"),
                    });
                }
            }
        }
        let mut rows = adjacency.off_diagonal_rows()?;
        let reversed: Vec<(u32, u32)> = rows
            .iter()
            .enumerate()
            .flat_map(|(i, row)| row.iter().map(move |&j| (j, i as u32)))
            .collect();
        for (j, i) in reversed {
            rows[j as usize].push(i);
        }
        if sampled.len() >= 2 && k > 0 {
            let sampled_points: Vec<[f32; 3]> =
                sampled.iter().map(|&i| points[i as usize]).collect();
            let knn = SpatialIndex::new(&sampled_points)?.knn_graph(k.min(sampled.len() - 1))?;
            for (a, neighbours) in knn.indices.chunks(knn.k).enumerate() {
                let i = sampled[a];
                for &b in neighbours {
                    let j = sampled[b as usize];
                    rows[i as usize].push(j);
                    rows[j as usize].push(i);
                }
            }
        }
        let mut dual_edges = Vec::with_capacity(3 * dual.len());
        for &[a, b, c] in dual {
            for (u, v) in [(a, b), (b, c), (c, a)] {
                let (Some(&i), Some(&j)) = (sampled.get(u as usize), sampled.get(v as usize))
                else {
                    return Err(Error::Invalid {
                        what: format!("dual triangle [{a}, {b}, {c}]"),
                        reason: format!("corner outside the {} sampled vertices", sampled.len()),
                    });
                };
                if i != j {
                    rows[i as usize].push(j);
                    rows[j as usize].push(i);
                    dual_edges.push((u.min(v), u.max(v)));
                }
            }
        }
        rows.par_iter_mut().for_each(|row| {
            row.sort_unstable();
            row.dedup();
        });
        // The pairs A_s is evaluated on: sampled vertices linked in the extended graph
        // (sorted, for binary search below).
        let links: Vec<Vec<u32>> = sampled
            .iter()
            .map(|&i| {
                let mut linked: Vec<u32> = rows[i as usize]
                    .iter()
                    .map(|&j| sample_position[j as usize])
                    .filter(|&b| b != u32::MAX)
                    .collect();
                linked.sort_unstable();
                linked
            })
            .collect();
        let conv_slots = NeighbourSlots::from_rows(&rows, device)?;
        let attention_rows: Vec<Vec<u32>> = rows
            .iter()
            .enumerate()
            .map(|(i, row)| {
                std::iter::once(i as u32)
                    .chain(row.iter().copied())
                    .collect()
            })
            .collect();
        let attention_slots = NeighbourSlots::from_rows(&attention_rows, device)?;
        let width = attention_slots.width();
        let mask: Vec<f32> = attention_rows
            .iter()
            .flat_map(|row| {
                (0..width).map(move |s| if s < row.len() { 0.0 } else { EMPTY_SLOT_LOGIT })
            })
            .collect();
        let pattern = SimplifiedAdjacencyPattern::new(&rows, width, &sample_position, &links)
            .map_err(|reason| Error::Invalid {
                what: "extended graph".into(),
                reason,
            })?;
        let pairs = links
            .iter()
            .enumerate()
            .flat_map(|(a, row)| row.iter().map(move |&b| [a as u32, b]))
            .collect();
        Ok(Self {
            conv_slots,
            attention_mask: Tensor::from_vec(mask, (n, width), device)?,
            attention_slots,
            pairs,
            pattern: Arc::new(pattern),
            sampled: sampled.to_vec(),
            dual_edges,
        })
    }

    /// The sampled vertices, in the numbering of `A_s`.
    pub fn sampled(&self) -> &[u32] {
        &self.sampled
    }

    /// The non-zero pattern of `A_s`: `(a, b)` pairs of sampled positions, sorted, `a ≠ b`,
    /// symmetric.
    pub fn pairs(&self) -> &[[u32; 2]] {
        &self.pairs
    }

    /// Eq. 6.3-6.4: the values of `A_s` on [`Self::pairs`] from the attention weights
    /// `attention: (N, W)` (rows over the attention slots).
    pub(crate) fn simplified_adjacency(&self, attention: &Tensor) -> Result<Tensor> {
        Ok(simplified_adjacency(attention, &self.pattern)?)
    }

    /// The index in [`Self::pairs`] of `(a, b)`, when it is non-zero.
    pub fn pair_index(&self, a: u32, b: u32) -> Option<usize> {
        self.pairs.binary_search(&[a, b]).ok()
    }

    /// The strongest entries of `A_s`: for every sampled vertex its `k` largest `values` (on
    /// [`Self::pairs`], ties by index), and the dual's edges, symmetrised by union, as an
    /// `M×M` pattern of ones (for [`meshgnn_graph::candidate_triangles`]; with the dual's
    /// edges every dual triangle is a candidate, also where a sampled vertex of a small mesh
    /// has more than `k` strong links).
    pub fn strongest_pattern(&self, values: &[f32], k: usize) -> Result<CsrMatrix> {
        let mut row_starts = vec![0];
        row_starts
            .extend((1..self.pairs.len()).filter(|&e| self.pairs[e][0] != self.pairs[e - 1][0]));
        row_starts.push(self.pairs.len());
        let mut kept: Vec<(u32, u32, f32)> = row_starts
            .par_windows(2)
            .flat_map_iter(|span| {
                let mut row: Vec<usize> = (span[0]..span[1]).collect();
                row.sort_by(|&x, &y| values[y].total_cmp(&values[x]).then(x.cmp(&y)));
                row.truncate(k);
                row.into_iter().flat_map(|e| {
                    let [a, b] = self.pairs[e];
                    [(a, b, 1.0), (b, a, 1.0)]
                })
            })
            .collect();
        for &(a, b) in &self.dual_edges {
            kept.push((a, b, 1.0));
            kept.push((b, a, 1.0));
        }
        kept.par_sort_unstable_by_key(|t| (t.0, t.1));
        kept.dedup_by_key(|t| (t.0, t.1));
        let m = self.sampled.len();
        Ok(CsrMatrix::from_triplets(m, m, &kept)?)
    }
}
