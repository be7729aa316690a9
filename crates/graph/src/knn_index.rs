//! A reusable k-NN index over 3-d points: one kd-tree built once and queried for both the
//! k-NN graph of the points themselves (projector GNN, thesis eq. 5.4, k = 7) and the
//! neighbours of other query points among them (AttRef, eq. 5.5, k = 15; Chamfer eq. 5.6-5.7).
//! [`crate::knn_graph`] and [`crate::knn_query`] are thin wrappers around it, so results are
//! identical whichever entry point is used (same conventions: nearest first, ties by index).

use crate::kd_tree::KdTree;
use crate::knn_graph::{Neighbours, check_finite, check_u32_len, run_queries};
use crate::{Error, Result};

/// Leaf size of the kd-tree for k-NN queries (a common choice for k ≈ 7-20; not tuned).
const LEAF_SIZE: usize = 16;

/// A kd-tree over `points: #P×3`, built once in O(P log P) (parallel) and queried many times.
#[derive(Debug, Clone)]
pub struct KnnIndex {
    tree: KdTree,
    /// The indexed points in their original order (the queries of [`KnnIndex::graph`]).
    points: Vec<[f32; 3]>,
}

impl KnnIndex {
    /// Builds the index over `points: #P×3`. Errors when a coordinate is NaN/infinite or
    /// `#P` does not fit `u32` indices.
    ///
    /// ```
    /// use meshgnn_graph::KnnIndex;
    /// let index = KnnIndex::new(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])?;
    /// assert_eq!(index.len(), 2);
    /// # Ok::<(), meshgnn_graph::Error>(())
    /// ```
    pub fn new(points: &[[f32; 3]]) -> Result<Self> {
        check_u32_len(points.len(), "points")?;
        check_finite(points, "point")?;
        Ok(Self {
            tree: KdTree::new(points, LEAF_SIZE),
            points: points.to_vec(),
        })
    }

    /// Number of indexed points #P.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True when no point is indexed.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Eq. 5.4 graph: for each indexed point its `k` nearest *other* points, `#P×k`
    /// (= [`crate::knn_graph`]). Errors when `k == 0` or `k >= #P`.
    ///
    /// ```
    /// use meshgnn_graph::KnnIndex;
    /// let index = KnnIndex::new(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [3.0, 0.0, 0.0]])?;
    /// assert_eq!(index.graph(1)?.indices, vec![1, 0, 1]);
    /// # Ok::<(), meshgnn_graph::Error>(())
    /// ```
    pub fn graph(&self, k: usize) -> Result<Neighbours> {
        let n = self.points.len();
        if k == 0 || k >= n {
            return Err(Error::InvalidParameter {
                name: "k",
                message: format!("must be in 1..{n} for {n} points"),
            });
        }
        Ok(run_queries(&self.tree, &self.points, k, true))
    }

    /// For each of `queries: #Q×3`, its `k` nearest indexed points, `#Q×k`
    /// (= [`crate::knn_query`]; eq. 5.5 AttRef neighbourhoods). Errors when `k == 0`,
    /// `k > #P`, or a query coordinate is NaN/infinite.
    ///
    /// ```
    /// use meshgnn_graph::KnnIndex;
    /// let index = KnnIndex::new(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [3.0, 0.0, 0.0]])?;
    /// let nn = index.query(&[[2.9, 0.0, 0.0]], 2)?;
    /// assert_eq!(nn.indices, vec![2, 1]);
    /// # Ok::<(), meshgnn_graph::Error>(())
    /// ```
    pub fn query(&self, queries: &[[f32; 3]], k: usize) -> Result<Neighbours> {
        let n = self.points.len();
        if k == 0 || k > n {
            return Err(Error::InvalidParameter {
                name: "k",
                message: format!("must be in 1..={n} for {n} points"),
            });
        }
        check_finite(queries, "query")?;
        Ok(run_queries(&self.tree, queries, k, false))
    }
}
