//! k nearest neighbours of every point of a cloud, shared by the curvature operators of thesis
//! section 5.3.1 (private to the crate).
//!
//! # Conventions
//! The neighbourhood `N_i` of eq. 5.1 is the `k` nearest points *other than* `p_i` (the point
//! itself would add a zero row to the covariance of eq. 5.1 and a weight-1 term to eq. 5.3).
//! With duplicates of `p_i` in the cloud, the duplicates are neighbours at distance 0. Ties are
//! broken by the kd-tree deterministically. Built on kiddo's immutable kd-tree.

use std::num::NonZero;

use kiddo::SquaredEuclidean;
use kiddo::immutable::float::kdtree::ImmutableKdTree;

use crate::error::{Error, Result};
use crate::tri_mesh::check_finite;

/// The kd-tree type used for point clouds (`u32` items: clouds up to 4·10⁹ points).
pub(crate) type PointTree = ImmutableKdTree<f32, u32, 3, 32>;

/// Validates `points: #P×3` and `k` for a self-excluding k-NN query and builds the tree.
pub(crate) fn build_tree(points: &[[f32; 3]], k: usize) -> Result<(PointTree, NonZero<usize>)> {
    if points.is_empty() {
        return Err(Error::Empty {
            what: "point cloud",
        });
    }
    check_finite("point", points)?;
    if u32::try_from(points.len()).is_err() {
        return Err(Error::InvalidParameter {
            name: "points",
            message: format!("{} points exceed the 2^32 supported", points.len()),
        });
    }
    if k < 2 || k >= points.len() {
        return Err(Error::InvalidParameter {
            name: "k",
            message: format!(
                "need 2 <= k < #points ({}) neighbours, got {k}",
                points.len()
            ),
        });
    }
    let query = NonZero::new(k + 1).ok_or(Error::InvalidParameter {
        name: "k",
        message: "k + 1 overflows".into(),
    })?;
    Ok((PointTree::new_from_slice(points), query))
}

/// Calls `visit(j, squared distance)` for the `k` nearest neighbours of point `i` other than
/// `i` itself, nearest first. `query` is `k + 1` from [`build_tree`].
#[inline]
pub(crate) fn for_each_neighbour(
    tree: &PointTree,
    points: &[[f32; 3]],
    i: usize,
    query: NonZero<usize>,
    mut visit: impl FnMut(usize, f32),
) {
    let found = tree.nearest_n::<SquaredEuclidean>(&points[i], query);
    // Drop `i` itself; if a duplicate pushed it out of the result, drop the farthest instead.
    let skip = found
        .iter()
        .position(|n| n.item as usize == i)
        .unwrap_or(found.len().saturating_sub(1));
    for (position, n) in found.iter().enumerate() {
        if position != skip {
            visit(n.item as usize, n.distance);
        }
    }
}
