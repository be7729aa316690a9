//! k-nearest-neighbour graphs over 3-d points: the graph of the point-cloud projector's GNN
//! layer (thesis eq. 5.4, k = 7), of AttRef (eq. 5.5, k = 15), of the edge predictor's extended
//! adjacency (ch. 6.3, k = 15) and the queries of the Chamfer distances. Thin wrappers over
//! [`meshgnn_geometry::SpatialIndex`], the workspace's one spatial index: build the index
//! yourself to query the same points several times.
//!
//! # Conventions
//! - `indices` is `#Q×k` row-major `u32`; row `i` lists the neighbours of point (query) `i`
//!   nearest first; `squared_distances` is aligned with it (`f32`, `dx·dx + dy·dy + dz·dz`).
//! - Ties in distance are broken by the smaller index, so results are deterministic and
//!   independent of the thread count.
//! - [`knn_graph`] excludes the point itself (by index; coincident duplicates are neighbours
//!   at distance 0).
//! - O(P log P) on any input, duplicate and collinear points included (see the index's notes).

pub use meshgnn_geometry::Neighbours;
use meshgnn_geometry::SpatialIndex;

use crate::{Error, Result};

/// Checks that every coordinate is finite; the error names the first bad point.
pub(crate) fn check_finite(points: &[[f32; 3]], what: &'static str) -> Result<()> {
    match meshgnn_geometry::vec3::first_non_finite(points) {
        Some(index) => Err(Error::NonFinite { what, index }),
        None => Ok(()),
    }
}

/// Checks that a point count fits `u32` indices.
pub(crate) fn check_u32_len(len: usize, what: &'static str) -> Result<()> {
    if u32::try_from(len).is_err() {
        return Err(Error::InvalidParameter {
            name: what,
            message: format!("{len} elements do not fit u32 indices"),
        });
    }
    Ok(())
}

/// The k-NN graph of `points: #P×3`: for each point its `k` nearest *other* points
/// (ch. 5.3.2, eq. 5.4: "k-nearest neighbours graph, k = 7"). O(P log P), parallel.
///
/// Errors when `k == 0`, `k >= #P`, or a coordinate is NaN/infinite.
///
/// ```
/// use meshgnn_graph::knn_graph;
/// let points = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [3.0, 0.0, 0.0]];
/// let nn = knn_graph(&points, 1)?;
/// assert_eq!(nn.indices, vec![1, 0, 1]);
/// assert_eq!(nn.squared_distances, vec![1.0, 1.0, 4.0]);
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn knn_graph(points: &[[f32; 3]], k: usize) -> Result<Neighbours> {
    if k == 0 || k >= points.len() {
        return Err(Error::InvalidParameter {
            name: "k",
            message: format!("must be in 1..{} for {} points", points.len(), points.len()),
        });
    }
    check_u32_len(points.len(), "points")?;
    check_finite(points, "point")?;
    Ok(SpatialIndex::new(points)?.knn_graph(k)?)
}

/// For each of `queries: #Q×3`, its `k` nearest of `points: #P×3` (a query coinciding with a
/// point finds it at distance 0). Used by the Chamfer distances (eq. 5.6-5.7) and AttRef
/// (eq. 5.5). O((P + Q) log P), parallel over queries. Build a [`SpatialIndex`] instead to
/// query the same points several times.
///
/// Errors when `k == 0`, `k > #P`, or a coordinate is NaN/infinite.
///
/// ```
/// use meshgnn_graph::knn_query;
/// let points = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [3.0, 0.0, 0.0]];
/// let nn = knn_query(&[[2.9, 0.0, 0.0]], &points, 2)?;
/// assert_eq!(nn.indices, vec![2, 1]);
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn knn_query(queries: &[[f32; 3]], points: &[[f32; 3]], k: usize) -> Result<Neighbours> {
    if k == 0 || k > points.len() {
        return Err(Error::InvalidParameter {
            name: "k",
            message: format!(
                "must be in 1..={} for {} points",
                points.len(),
                points.len()
            ),
        });
    }
    check_u32_len(points.len(), "points")?;
    check_finite(points, "point")?;
    check_finite(queries, "query")?;
    Ok(SpatialIndex::new(points)?.knn(queries, k)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshgnn_geometry::squared_distance;
    use rand::{Rng, SeedableRng, rngs::StdRng};

    fn brute(queries: &[[f32; 3]], points: &[[f32; 3]], k: usize, exclude_self: bool) -> Vec<u32> {
        queries
            .iter()
            .enumerate()
            .flat_map(|(i, q)| {
                let mut all: Vec<(f32, u32)> = points
                    .iter()
                    .enumerate()
                    .filter(|&(j, _)| !(exclude_self && i == j))
                    .map(|(j, p)| (squared_distance(p, q), j as u32))
                    .collect();
                all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                all.into_iter().take(k).map(|x| x.1).collect::<Vec<_>>()
            })
            .collect()
    }

    fn random_points(seed: u64, n: usize, duplicates: bool) -> Vec<[f32; 3]> {
        let mut rng = StdRng::seed_from_u64(seed);
        let mut pts: Vec<[f32; 3]> = (0..n)
            .map(|_| [rng.random(), rng.random(), rng.random()])
            .collect();
        if duplicates {
            // Every fourth point copies an earlier one; a grid gives many equal distances.
            for i in (3..n).step_by(4) {
                pts[i] = pts[rng.random_range(0..i)];
            }
            for (i, p) in pts.iter_mut().enumerate().take(n / 3) {
                *p = [(i % 5) as f32, ((i / 5) % 5) as f32, 0.0];
            }
        }
        pts
    }

    #[test]
    fn graph_matches_brute_force_with_and_without_duplicates() {
        for (seed, dup) in [(1, false), (2, true), (3, true)] {
            let pts = random_points(seed, 700, dup);
            for k in [1, 7, 15] {
                let nn = knn_graph(&pts, k).unwrap();
                assert_eq!(nn.indices, brute(&pts, &pts, k, true), "seed {seed} k {k}");
                for (i, row) in nn.indices.chunks(k).enumerate() {
                    assert!(!row.contains(&(i as u32)));
                }
            }
        }
    }

    #[test]
    fn query_matches_brute_force() {
        let pts = random_points(4, 500, true);
        let queries = random_points(5, 200, false);
        let nn = knn_query(&queries, &pts, 9).unwrap();
        assert_eq!(nn.indices, brute(&queries, &pts, 9, false));
        for (i, &j) in nn.indices.iter().enumerate() {
            let q = &queries[i / 9];
            assert_eq!(
                nn.squared_distances[i],
                squared_distance(&pts[j as usize], q)
            );
        }
    }

    #[test]
    fn index_graph_and_query_equal_the_free_functions() {
        let pts = random_points(6, 600, true);
        let queries = random_points(7, 150, false);
        let index = SpatialIndex::new(&pts).unwrap();
        for k in [1, 7, 15] {
            let g = index.knn_graph(k).unwrap();
            assert_eq!(g, knn_graph(&pts, k).unwrap(), "graph k {k}");
            assert_eq!(g.indices, brute(&pts, &pts, k, true), "graph k {k}");
            let q = index.knn(&queries, k).unwrap();
            assert_eq!(q, knn_query(&queries, &pts, k).unwrap(), "query k {k}");
            assert_eq!(q.indices, brute(&queries, &pts, k, false), "query k {k}");
        }
        assert_eq!(index.len(), 600);
        assert!(index.knn_graph(600).is_err());
        assert!(index.knn(&queries, 601).is_err());
        assert!(index.knn(&[[f32::NAN, 0.0, 0.0]], 1).is_err());
    }

    #[test]
    fn all_coincident_points_take_neighbours_in_index_order() {
        let pts = vec![[0.5f32, 0.5, 0.5]; 100];
        let nn = knn_graph(&pts, 3).unwrap();
        assert_eq!(nn.row(0), &[1, 2, 3]);
        assert_eq!(nn.row(2), &[0, 1, 3]);
        assert!(nn.squared_distances.iter().all(|&d| d == 0.0));
    }

    #[test]
    fn rejects_bad_input() {
        let pts = [[0.0f32; 3], [1.0, 0.0, 0.0]];
        assert!(knn_graph(&pts, 2).is_err());
        assert!(knn_graph(&pts, 0).is_err());
        assert!(matches!(
            knn_graph(&[[0.0, 0.0, 0.0], [f32::NAN, 0.0, 0.0], [1.0, 1.0, 1.0]], 1),
            Err(Error::NonFinite { index: 1, .. })
        ));
        assert!(knn_query(&[[0.0; 3]], &pts, 3).is_err());
    }

    #[test]
    fn identical_and_collinear_clouds_of_200k_points() {
        // Degenerate inputs in O(n log n) (without the index's smallest-index pruning the
        // identical cloud costs 4·10¹⁰ distance evaluations).
        let n = 200_000;
        let same = vec![[0.5f32, 0.5, 0.5]; n];
        let nn = knn_graph(&same, 7).unwrap();
        assert_eq!(nn.row(0), &[1, 2, 3, 4, 5, 6, 7]);
        assert_eq!(nn.row(n - 1), &[0, 1, 2, 3, 4, 5, 6]);
        assert!(nn.squared_distances.iter().all(|&d| d == 0.0));
        // Equally spaced on a line: both neighbours at each distance, the smaller index first.
        let line: Vec<[f32; 3]> = (0..n).map(|i| [i as f32 * 0.5, 0.0, 0.0]).collect();
        let nn = knn_graph(&line, 4).unwrap();
        assert_eq!(nn.row(1000), &[999, 1001, 998, 1002]);
        assert_eq!(nn.row(0), &[1, 2, 3, 4]);
        let q = knn_query(&same[..10], &line, 2).unwrap();
        assert_eq!(q.row(9), &[1, 0]);
    }
}
