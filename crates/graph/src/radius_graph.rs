//! Radius (ε-ball) neighbourhoods of 3-d points: the fixed-scale alternative to k-NN graphs
//! for point-cloud GNNs (PointNet++ ball query, Qi et al. 2017, NeurIPS), and the
//! neighbourhoods of curvature-style features at a metric scale (thesis ch. 5.3.1).
//!
//! # Conventions
//! CSR layout: row `i` is `offsets[i]..offsets[i+1]` of `indices` / `squared_distances`,
//! sorted by `(squared distance, index)`, the point itself excluded, points at exactly the
//! radius included. `max_neighbours` keeps the nearest ones only (ball query with a cap).
//! - Queries go to [`meshgnn_geometry::SpatialIndex`]; with a cap each row costs a k-NN query
//!   however many points share the ball (duplicates), without one the cost follows the output.

use meshgnn_geometry::SpatialIndex;
use rayon::prelude::*;

use crate::knn_graph::{check_finite, check_u32_len};
use crate::{Error, Result};

/// Neighbours within a radius, per point, in CSR layout.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RadiusNeighbours {
    /// `#P + 1` row offsets.
    pub offsets: Vec<usize>,
    /// Neighbour indices, nearest first within each row.
    pub indices: Vec<u32>,
    /// Squared distances aligned with `indices`.
    pub squared_distances: Vec<f32>,
}

impl RadiusNeighbours {
    /// The neighbours of point `i` (empty when out of range).
    pub fn row(&self, i: usize) -> &[u32] {
        match (self.offsets.get(i), self.offsets.get(i + 1)) {
            (Some(&s), Some(&e)) => self.indices.get(s..e).unwrap_or(&[]),
            _ => &[],
        }
    }
}

/// For each of `points: #P×3`, the other points within `radius` (inclusive), nearest first,
/// at most `max_neighbours` of them when given. O(P log P + output), parallel; with
/// `max_neighbours = m`, O(P (log P + m)) whatever the density (duplicates included).
///
/// Errors when `radius` is negative or not finite, or a coordinate is NaN/infinite.
///
/// ```
/// use meshgnn_graph::radius_graph;
/// let points = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [3.0, 0.0, 0.0]];
/// let g = radius_graph(&points, 2.0, None)?;
/// assert_eq!(g.row(0), &[1]);
/// assert_eq!(g.row(1), &[0, 2]); // both at distance ≤ 2; 0 is nearer
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn radius_graph(
    points: &[[f32; 3]],
    radius: f32,
    max_neighbours: Option<usize>,
) -> Result<RadiusNeighbours> {
    if !(radius.is_finite() && radius >= 0.0) {
        return Err(Error::InvalidParameter {
            name: "radius",
            message: format!("{radius} is not a finite distance >= 0"),
        });
    }
    check_u32_len(points.len(), "points")?;
    check_finite(points, "point")?;
    let index = SpatialIndex::new(points)?;
    let r2 = radius * radius;
    let rows: Vec<Vec<(f32, u32)>> = points
        .par_iter()
        .enumerate()
        .map(|(i, p)| {
            let mut found = Vec::new();
            match max_neighbours {
                Some(cap) => index.nearest_within(p, cap, r2, Some(i as u32), &mut found),
                None => index.within(p, r2, Some(i as u32), &mut found),
            }
            found
        })
        .collect();
    let mut offsets = Vec::with_capacity(points.len() + 1);
    offsets.push(0);
    let total: usize = rows.iter().map(Vec::len).sum();
    let mut indices = Vec::with_capacity(total);
    let mut squared_distances = Vec::with_capacity(total);
    for row in rows {
        for (d, j) in row {
            indices.push(j);
            squared_distances.push(d);
        }
        offsets.push(indices.len());
    }
    Ok(RadiusNeighbours {
        offsets,
        indices,
        squared_distances,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshgnn_geometry::squared_distance;
    use rand::{Rng, SeedableRng, rngs::StdRng};

    #[test]
    fn matches_brute_force_including_boundary_and_duplicates() {
        let mut rng = StdRng::seed_from_u64(8);
        let mut pts: Vec<[f32; 3]> = (0..800)
            .map(|_| [rng.random(), rng.random(), rng.random()])
            .collect();
        // Exact-radius and coincident points on a 0.25 lattice.
        for (i, p) in pts.iter_mut().enumerate().take(200) {
            *p = [(i % 4) as f32 * 0.25, ((i / 4) % 4) as f32 * 0.25, 0.0];
        }
        let radius = 0.25f32;
        for cap in [None, Some(5)] {
            let g = radius_graph(&pts, radius, cap).unwrap();
            for (i, p) in pts.iter().enumerate() {
                let mut want: Vec<(f32, u32)> = pts
                    .iter()
                    .enumerate()
                    .filter(|&(j, q)| j != i && squared_distance(q, p) <= radius * radius)
                    .map(|(j, q)| (squared_distance(q, p), j as u32))
                    .collect();
                want.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                want.truncate(cap.unwrap_or(usize::MAX));
                let want: Vec<u32> = want.into_iter().map(|x| x.1).collect();
                assert_eq!(g.row(i), want.as_slice(), "point {i}");
            }
        }
    }

    #[test]
    fn rejects_bad_radius() {
        assert!(radius_graph(&[[0.0; 3]], -1.0, None).is_err());
        assert!(radius_graph(&[[0.0; 3]], f32::NAN, None).is_err());
        assert_eq!(
            radius_graph(&[[0.0; 3]], 1.0, None).unwrap().row(0),
            &[] as &[u32]
        );
    }

    #[test]
    fn capped_ball_query_on_200k_identical_points() {
        // Every point is in every ball; the cap keeps each row a k-NN query.
        let n = 200_000;
        let same = vec![[0.0f32, 1.0, 0.0]; n];
        let g = radius_graph(&same, 0.1, Some(3)).unwrap();
        assert_eq!(g.row(0), &[1, 2, 3]);
        assert_eq!(g.row(n - 1), &[0, 1, 2]);
        assert_eq!(g.offsets.last(), Some(&(3 * n)));
    }
}
