//! Curvature error CE (thesis eq. 5.8): RMS difference of the Gaussian-weighted mean curvature
//! (eq. 5.3) of the original and the simplified cloud, both measured at the same locations and
//! the same physical scale ([`super::matched_scale_curvature`]).

use crate::Result;
use crate::metrics::matched_scale_curvature::{matched_scale_curvature, rms_difference};

/// Eq. 5.8: `CE = ( mean_{q∈R} (K̄_1(q) − K̄_2(q))² )^{1/2}` for `original: #P1×3` and
/// `simplified: #P2×3`, with `R` the original's reference points and both `K̄` at the kernel
/// radius that holds `k` simplified points ([`super::matched_scale_curvature`]). Curvature of
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
    let m = matched_scale_curvature(original, simplified, k, 1.0)?;
    Ok(rms_difference(
        &m.original_at_reference.mean_curvature,
        &m.simplified_at_reference.mean_curvature,
    ))
}
