//! Curvature error CE (thesis eq. 5.8): RMS difference of the Gaussian-weighted mean curvature
//! (eq. 5.3) between each original point and its nearest simplified point.

use crate::metrics::nearest_value_error::nearest_value_error;
use crate::metrics::point_cloud_evaluation::MAX_EVALUATION_CURVATURE_NEIGHBOURS;
use crate::validate::check_points;
use crate::{Error, Result};
use meshgnn_geometry::{CurvatureFeatures, curvature_features};

/// Eq. 5.1-5.3 on `points: #P×3` with `k` neighbours, `k` capped at `#P − 1` so that a small
/// simplified cloud still gets features. Fails for fewer than 3 points or `k` outside
/// `2..=MAX_EVALUATION_CURVATURE_NEIGHBOURS`.
pub(crate) fn features_for(
    what: &'static str,
    points: &[[f32; 3]],
    k: usize,
) -> Result<CurvatureFeatures> {
    check_points(what, points)?;
    if !(2..=MAX_EVALUATION_CURVATURE_NEIGHBOURS).contains(&k) {
        return Err(Error::InvalidParameter {
            name: "k",
            message: format!(
                "curvature needs 2 to {MAX_EVALUATION_CURVATURE_NEIGHBOURS} neighbours, got {k}"
            ),
        });
    }
    if points.len() < 3 {
        return Err(Error::InvalidParameter {
            name: what,
            message: format!("curvature needs at least 3 points, got {}", points.len()),
        });
    }
    Ok(curvature_features(points, k.min(points.len() - 1))?)
}

/// Eq. 5.8: `CE = ( mean_{x∈P1} (K̄_1(x) − K̄_2(NN(x, P2)))² )^{1/2}` for `original: #P1×3` and
/// `simplified: #P2×3`, each cloud's mean curvature `K̄` estimated on that cloud with `k`
/// nearest neighbours (eq. 5.1-5.3, the geometry crate's `curvature_features`). Curvature of
/// eq. 5.2 is dimensionless in [0, 1/3], and so is CE.
///
/// ```
/// use meshgnn_geometry::icosphere;
/// use meshgnn_losses::metrics::curvature_error;
/// let sphere = icosphere(3);
/// assert_eq!(curvature_error(sphere.vertices(), sphere.vertices(), 16)?, 0.0);
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn curvature_error(original: &[[f32; 3]], simplified: &[[f32; 3]], k: usize) -> Result<f64> {
    let (a, b) = rayon::join(
        || features_for("original points", original, k),
        || features_for("simplified points", simplified, k),
    );
    let (a, b) = (a?, b?);
    nearest_value_error(original, &a.mean_curvature, simplified, &b.mean_curvature)
}
