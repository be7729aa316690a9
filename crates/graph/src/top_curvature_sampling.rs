//! Top-curvature point sampling (TCP), the saliency baseline of thesis ch. 5.5 ("a top
//! curvature points sampling (TCP) where the top-k curvature points are selected from the input
//! point cloud", Table 5.1).
//!
//! # Conventions
//! - `curvature: #N` holds one value per point (the app passes the Gaussian-weighted mean
//!   curvature `K̄` of eq. 5.3 from `meshgnn_geometry::curvature_features`); any finite values
//!   work, negative included.
//! - The result is `k` distinct `u32` indices ordered by decreasing curvature, so any prefix is
//!   itself the top of the cloud.
//! - Ties: equal curvatures are taken in increasing index order. The result depends only on
//!   `(curvature, k)`: deterministic, no seed.
//! - O(N) expected to find the top `k` (`select_nth_unstable_by`), then O(k log k) to order them.

use std::cmp::Ordering;

use crate::{Error, Result};

/// Larger curvature first, then smaller index: the total order TCP ranks points by.
fn rank(curvature: &[f32], a: u32, b: u32) -> Ordering {
    let (ca, cb) = (curvature[a as usize], curvature[b as usize]);
    cb.total_cmp(&ca).then(a.cmp(&b))
}

/// TCP (ch. 5.5 baseline): the `k` indices of `curvature: #N` with the highest values, highest
/// first, ties to the smaller index.
///
/// Errors when `k > N`, `N` exceeds `u32` indices, or a value is NaN or infinite. `k == 0`
/// gives an empty result.
///
/// ```
/// use meshgnn_graph::top_curvature_sampling;
/// let curvature = [0.1, 0.5, 0.2, 0.5, 0.0];
/// // 0.5 twice (index 1 before 3), then 0.2.
/// assert_eq!(top_curvature_sampling(&curvature, 3)?, vec![1, 3, 2]);
/// assert!(top_curvature_sampling(&curvature, 6).is_err());
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn top_curvature_sampling(curvature: &[f32], k: usize) -> Result<Vec<u32>> {
    let n = curvature.len();
    if u32::try_from(n).is_err() {
        return Err(Error::InvalidParameter {
            name: "curvature",
            message: format!("{n} points exceed the 2^32 supported"),
        });
    }
    if k > n {
        return Err(Error::InvalidParameter {
            name: "k",
            message: format!("cannot keep {k} of {n} points"),
        });
    }
    if let Some(index) = curvature.iter().position(|c| !c.is_finite()) {
        return Err(Error::NonFinite {
            what: "curvature of point",
            index,
        });
    }
    if k == 0 {
        return Ok(Vec::new());
    }
    let mut order: Vec<u32> = (0..n as u32).collect();
    if k < n {
        order.select_nth_unstable_by(k - 1, |&a, &b| rank(curvature, a, b));
        order.truncate(k);
    }
    order.sort_unstable_by(|&a, &b| rank(curvature, a, b));
    Ok(order)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn keeps_exactly_the_highest_curvature_points() {
        // A hand-made cloud: corners (high curvature) among flat points (zero).
        let mut curvature = vec![0.0f32; 12];
        curvature[7] = 0.30;
        curvature[2] = 0.25;
        curvature[10] = 0.25;
        curvature[4] = 0.01;
        assert_eq!(top_curvature_sampling(&curvature, 1).unwrap(), vec![7]);
        assert_eq!(
            top_curvature_sampling(&curvature, 3).unwrap(),
            vec![7, 2, 10]
        );
        assert_eq!(
            top_curvature_sampling(&curvature, 4).unwrap(),
            vec![7, 2, 10, 4]
        );
        // Then the zeros, in index order.
        assert_eq!(
            top_curvature_sampling(&curvature, 6).unwrap(),
            vec![7, 2, 10, 4, 0, 1]
        );
    }

    #[test]
    fn negative_values_rank_below_zero() {
        let curvature = [-1.0, 0.0, -0.5];
        assert_eq!(
            top_curvature_sampling(&curvature, 3).unwrap(),
            vec![1, 2, 0]
        );
    }

    #[test]
    fn rejects_bad_input() {
        assert!(top_curvature_sampling(&[0.1, 0.2], 3).is_err());
        let err = top_curvature_sampling(&[0.1, f32::NAN], 1).unwrap_err();
        assert!(err.to_string().contains('1'), "{err}");
        assert!(top_curvature_sampling(&[], 0).unwrap().is_empty());
    }

    proptest! {
        #[test]
        fn matches_a_full_sort(values in proptest::collection::vec(0u8..8, 1..200), k in 0usize..200) {
            let curvature: Vec<f32> = values.iter().map(|&v| f32::from(v) * 0.1).collect();
            let k = k.min(curvature.len());
            let mut all: Vec<u32> = (0..curvature.len() as u32).collect();
            all.sort_by(|&a, &b| rank(&curvature, a, b));
            let picked = top_curvature_sampling(&curvature, k).unwrap();
            prop_assert_eq!(&picked[..], &all[..k]);
        }
    }
}
