//! Mean per-vertex Euclidean error between two registered meshes (same vertex order): the
//! reconstruction error of thesis ch. 3.4 (generalisation, Table 3.2) and ch. 4.4 (Table 4.2).

use crate::Result;
use crate::deterministic_sum::deterministic_sum;
use crate::validate::{check_len, check_points};
use meshgnn_geometry::vec3::squared_distance_f64;

/// Mean over vertices of ‖a_v − b_v‖ for `a, b: #V×3` in correspondence (same units as the
/// input, e.g. mm for Table 3.2). Accumulated in `f64`, parallel and order-deterministic.
///
/// Fails when the sets are empty, differ in length or hold non-finite coordinates.
///
/// ```
/// use meshgnn_losses::metrics::per_vertex_error;
/// let a = [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]];
/// let b = [[3.0, 4.0, 0.0], [1.0, 1.0, 1.0]];
/// assert_eq!(per_vertex_error(&a, &b)?, 2.5); // (5 + 0) / 2
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn per_vertex_error(a: &[[f32; 3]], b: &[[f32; 3]]) -> Result<f64> {
    check_points("predicted vertices", a)?;
    check_points("target vertices", b)?;
    check_len("target vertices", a.len(), b.len())?;
    let total = deterministic_sum(a.len(), |i| match (a.get(i), b.get(i)) {
        (Some(p), Some(q)) => squared_distance_f64(p, q).sqrt(),
        _ => 0.0,
    });
    Ok(total / a.len() as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_for_identical_and_rejects_mismatch() {
        let a = [[0.1, 0.2, 0.3], [1.0, 2.0, 3.0]];
        assert_eq!(per_vertex_error(&a, &a).unwrap(), 0.0);
        assert!(per_vertex_error(&a, &a[..1]).is_err());
    }

    #[test]
    fn hand_computed() {
        let a = [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]];
        let b = [[1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 3.0]];
        assert!((per_vertex_error(&a, &b).unwrap() - 2.0).abs() < 1e-12);
    }
}
