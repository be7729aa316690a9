//! Nearest-neighbour queries over a fixed 3-d point set for the metrics and losses of this
//! crate: [`meshgnn_geometry::SpatialIndex`] (the workspace's one spatial index) with squared
//! distances recomputed in `f64`.
//!
//! Queries run in parallel (rayon), each in O(log n) on any input, duplicate points included,
//! and each result depends only on its query (ties go to the smaller index), so the answer is
//! the same for any thread count. Distances are recomputed in `f64` from the stored
//! coordinates, so they are exact for the returned neighbour.

use meshgnn_geometry::SpatialIndex;
use meshgnn_geometry::vec3::squared_distance_f64;
use rayon::prelude::*;

/// The index over `points: #P×3`, answering nearest and k-nearest queries.
pub(crate) struct PointIndex<'a> {
    points: &'a [[f32; 3]],
    index: SpatialIndex,
}

impl<'a> PointIndex<'a> {
    /// Builds the index. `points` must be non-empty and finite: every caller checks them
    /// first with its own error naming the input; a set that is not (a caller bug) gives an
    /// index that finds nothing, so every distance is infinite rather than wrong.
    pub(crate) fn new(points: &'a [[f32; 3]]) -> Self {
        match SpatialIndex::new(points) {
            Ok(index) => Self { points, index },
            Err(_) => Self {
                points: &[],
                index: SpatialIndex::default(),
            },
        }
    }

    /// Index of the nearest indexed point to `query` (the smallest index among equally near
    /// ones) and its squared distance; `(0, ∞)` when nothing is indexed.
    pub(crate) fn nearest(&self, query: &[f32; 3]) -> (usize, f64) {
        self.nearest_k(query, 1)
            .first()
            .copied()
            .unwrap_or((0, f64::INFINITY))
    }

    /// For every query, the nearest indexed point and its squared distance (in parallel).
    pub(crate) fn nearest_all(&self, queries: &[[f32; 3]]) -> Vec<(usize, f64)> {
        queries.par_iter().map(|q| self.nearest(q)).collect()
    }

    /// The `k` nearest indexed points to `query`, nearest first by the `f64` distance (ties by
    /// index), as (index, squared distance). Returns fewer when fewer points are indexed;
    /// nothing when `k == 0`.
    pub(crate) fn nearest_k(&self, query: &[f32; 3], k: usize) -> Vec<(usize, f64)> {
        let mut found = Vec::with_capacity(k.min(self.points.len()));
        self.index.nearest(query, k, None, &mut found);
        let mut found: Vec<(usize, f64)> = found
            .into_iter()
            .filter_map(|(_, j)| {
                let index = j as usize;
                self.points
                    .get(index)
                    .map(|p| (index, squared_distance_f64(p, query)))
            })
            .collect();
        found.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
        found
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn duplicates_resolve_to_the_smallest_index_with_exact_distances() {
        let pts = vec![[0.25f32, 0.5, 1.0]; 1000];
        let index = PointIndex::new(&pts);
        assert_eq!(index.nearest(&[0.25, 0.5, 2.0]), (0, 1.0));
        assert_eq!(
            index.nearest_k(&[0.25, 0.5, 1.0], 3),
            vec![(0, 0.0), (1, 0.0), (2, 0.0)]
        );
        let bad = [[f32::NAN, 0.0, 0.0]];
        assert_eq!(PointIndex::new(&bad).nearest(&[0.0; 3]), (0, f64::INFINITY));
    }

    #[test]
    fn metrics_on_200k_identical_and_collinear_points() {
        // The eval metrics' correspondences on degenerate clouds in O(n log n).
        use crate::metrics::{chamfer_distance, hausdorff_distance};
        let same = vec![[0.25f32, 0.5, 1.0]; 200_000];
        assert_eq!(
            chamfer_distance(&same, &same[..100_000])
                .unwrap()
                .symmetric_mean(),
            0.0
        );
        assert_eq!(hausdorff_distance(&same, &same[..100_000]).unwrap(), 0.0);
        let line: Vec<[f32; 3]> = (0..200_000).map(|i| [i as f32, 0.0, 0.0]).collect();
        let index = PointIndex::new(&line);
        assert_eq!(index.nearest(&[10.5, 0.0, 0.0]), (10, 0.25));
        assert_eq!(
            hausdorff_distance(&line, &line[..100_000]).unwrap(),
            100_000.0
        );
    }
}
