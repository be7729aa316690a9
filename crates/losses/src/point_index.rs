//! Nearest-neighbour queries over a fixed 3-d point set (a kiddo immutable k-d tree).
//!
//! Every metric and loss of this crate finds correspondences with this index: queries run in
//! parallel (rayon), each in O(log n), and each result depends only on its query, so the
//! answer is the same for any thread count. Squared distances are recomputed in `f64` from
//! the stored coordinates, so they are exact for the returned neighbour.

use kiddo::SquaredEuclidean;
use kiddo::immutable::float::kdtree::ImmutableKdTree;
use rayon::prelude::*;
use std::num::NonZero;

/// A k-d tree over `points: #P×3`, answering nearest and k-nearest queries.
pub(crate) struct PointIndex<'a> {
    points: &'a [[f32; 3]],
    tree: ImmutableKdTree<f32, u32, 3, 32>,
}

/// Squared Euclidean distance of two points, accumulated in `f64`.
pub(crate) fn squared_distance(a: &[f32; 3], b: &[f32; 3]) -> f64 {
    let dx = f64::from(a[0]) - f64::from(b[0]);
    let dy = f64::from(a[1]) - f64::from(b[1]);
    let dz = f64::from(a[2]) - f64::from(b[2]);
    dx * dx + dy * dy + dz * dz
}

impl<'a> PointIndex<'a> {
    /// Builds the tree. `points` must be non-empty and finite (checked by the callers).
    pub(crate) fn new(points: &'a [[f32; 3]]) -> Self {
        Self {
            points,
            tree: ImmutableKdTree::new_from_slice(points),
        }
    }

    /// Index of the nearest indexed point to `query` and its squared distance.
    pub(crate) fn nearest(&self, query: &[f32; 3]) -> (usize, f64) {
        let found = self.tree.nearest_one::<SquaredEuclidean>(query);
        let index = found.item as usize;
        let d = self
            .points
            .get(index)
            .map_or(f64::INFINITY, |p| squared_distance(p, query));
        (index, d)
    }

    /// For every query, the nearest indexed point and its squared distance (in parallel).
    pub(crate) fn nearest_all(&self, queries: &[[f32; 3]]) -> Vec<(usize, f64)> {
        queries.par_iter().map(|q| self.nearest(q)).collect()
    }

    /// The `k` nearest indexed points to `query`, nearest first, as (index, squared distance).
    /// Returns fewer when fewer points are indexed; nothing when `k == 0`.
    pub(crate) fn nearest_k(&self, query: &[f32; 3], k: usize) -> Vec<(usize, f64)> {
        let Some(k) = NonZero::new(k.min(self.points.len())) else {
            return Vec::new();
        };
        let mut found: Vec<(usize, f64)> = self
            .tree
            .nearest_n::<SquaredEuclidean>(query, k)
            .into_iter()
            .filter_map(|n| {
                let index = n.item as usize;
                self.points
                    .get(index)
                    .map(|p| (index, squared_distance(p, query)))
            })
            .collect();
        found.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
        found
    }
}
