//! Roughness error RE (thesis ch. 5.4): eq. 5.8 with roughness `R = |κ − K̄|` in place of the
//! mean curvature, on the same footing as CE ([`super::matched_scale_curvature`]).

use crate::Result;
use crate::metrics::matched_scale_curvature::{matched_scale_curvature, rms_difference};

/// RE: `( mean_{q∈R} (R_1(q) − R_2(q))² )^{1/2}` for `original: #P1×3` and
/// `simplified: #P2×3`, both roughness fields at the original's reference points and the
/// kernel radius that holds `k` simplified points. Dimensionless, like the curvature of
/// eq. 5.2.
///
/// ```
/// use meshgnn_geometry::icosphere;
/// use meshgnn_losses::metrics::roughness_error;
/// let sphere = icosphere(3);
/// assert_eq!(roughness_error(sphere.vertices(), sphere.vertices(), 16)?, 0.0);
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn roughness_error(original: &[[f32; 3]], simplified: &[[f32; 3]], k: usize) -> Result<f64> {
    let m = matched_scale_curvature(original, simplified, k, 1.0)?;
    Ok(rms_difference(
        &m.original_at_reference.roughness,
        &m.simplified_at_reference.roughness,
    ))
}
