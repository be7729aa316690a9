//! Roughness error RE (thesis ch. 5.4): eq. 5.8 with roughness `R = |κ − K̄|` in place of the
//! mean curvature.

use crate::Result;
use crate::metrics::curvature_error::features_for;
use crate::metrics::nearest_value_error::nearest_value_error;

/// RE: `( mean_{x∈P1} (R_1(x) − R_2(NN(x, P2)))² )^{1/2}` for `original: #P1×3` and
/// `simplified: #P2×3`, roughness from the geometry crate's `curvature_features` with `k`
/// neighbours on each cloud. Dimensionless, like the curvature of eq. 5.2.
///
/// ```
/// use meshgnn_geometry::icosphere;
/// use meshgnn_losses::metrics::roughness_error;
/// let sphere = icosphere(3);
/// assert_eq!(roughness_error(sphere.vertices(), sphere.vertices(), 16)?, 0.0);
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn roughness_error(original: &[[f32; 3]], simplified: &[[f32; 3]], k: usize) -> Result<f64> {
    let (a, b) = rayon::join(
        || features_for("original points", original, k),
        || features_for("simplified points", simplified, k),
    );
    let (a, b) = (a?, b?);
    nearest_value_error(original, &a.roughness, simplified, &b.roughness)
}
