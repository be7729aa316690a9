//! The neighbourhoods `N_i` of the curvature operators of thesis section 5.3.1 (eq. 5.1-5.3):
//! the `k` nearest points of every point other than itself, from [`SpatialIndex`]. The
//! features [`crate::curvature_features`] and [`crate::pca_normals_and_curvature`] both take
//! their neighbourhoods from this one function, so they agree by construction. (The fair
//! metrics and their loss use [`crate::kernel_neighbourhood`] instead: one physical radius.)
//!
//! # Conventions
//! The neighbourhood `N_i` of eq. 5.1 is the `k` nearest points *other than* `p_i` (the point
//! itself would add a zero row to the covariance of eq. 5.1 and a weight-1 term to eq. 5.3).
//! With duplicates of `p_i` in the cloud, the duplicates are neighbours at distance 0. Nearest
//! first, ties to the smaller index (the index's conventions).

use crate::error::{Error, Result};
use crate::spatial_index::{Neighbours, SpatialIndex};

/// `N_i` of eq. 5.1 for every point of `points: #P×3`: `#P×k` neighbour indices and squared
/// distances. O(P log P + P·k) on any input, duplicates included. Fails on an empty cloud, a
/// non-finite point, or `k` outside `2..#P`.
///
/// ```
/// use meshgnn_geometry::curvature_neighbourhoods;
/// let line = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 0.0, 0.0]];
/// let hoods = curvature_neighbourhoods(&line, 2)?;
/// assert_eq!(hoods.row(0), &[3, 1]); // the duplicate at distance 0 first
/// assert_eq!(hoods.row(1), &[0, 2]); // 0, 2 and 3 all at distance 1: the smaller indices
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn curvature_neighbourhoods(points: &[[f32; 3]], k: usize) -> Result<Neighbours> {
    if points.is_empty() {
        return Err(Error::Empty {
            what: "point cloud",
        });
    }
    let index = SpatialIndex::new(points)?;
    if k < 2 || k >= points.len() {
        return Err(Error::InvalidParameter {
            name: "k",
            message: format!(
                "need 2 <= k < #points ({}) neighbours, got {k}",
                points.len()
            ),
        });
    }
    index.knn_graph(k)
}
