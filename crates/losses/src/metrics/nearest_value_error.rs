//! The nearest-neighbour RMS difference of a per-point scalar field between two clouds: the
//! form shared by the curvature error CE (thesis eq. 5.8) and the roughness error RE (ch. 5.4).

use crate::Result;
use crate::deterministic_sum::deterministic_sum;
use crate::point_index::PointIndex;
use crate::validate::{check_len, check_points, check_scalars};

/// Eq. 5.8 with any scalar field: `( mean_{x∈A} (v_A(x) − v_B(NN(x, B)))² )^{1/2}` for
/// `points_a: #A×3`, `values_a: #A`, `points_b: #B×3`, `values_b: #B`. Units of the field.
///
/// ```
/// use meshgnn_losses::metrics::nearest_value_error;
/// let a = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]];
/// let b = [[0.1, 0.0, 0.0], [0.9, 0.0, 0.0]];
/// let e = nearest_value_error(&a, &[1.0, 2.0], &b, &[1.0, 5.0])?;
/// assert!((e - (4.5f64).sqrt()).abs() < 1e-12); // sqrt((0² + 3²) / 2)
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn nearest_value_error(
    points_a: &[[f32; 3]],
    values_a: &[f32],
    points_b: &[[f32; 3]],
    values_b: &[f32],
) -> Result<f64> {
    check_points("first point set", points_a)?;
    check_points("second point set", points_b)?;
    check_len("values of the first set", points_a.len(), values_a.len())?;
    check_len("values of the second set", points_b.len(), values_b.len())?;
    check_scalars("values of the first set", values_a)?;
    check_scalars("values of the second set", values_b)?;
    let tree = PointIndex::new(points_b);
    let sum = deterministic_sum(points_a.len(), |i| {
        let (Some(p), Some(&v)) = (points_a.get(i), values_a.get(i)) else {
            return 0.0;
        };
        let (j, _) = tree.nearest(p);
        let w = values_b.get(j).copied().unwrap_or(v);
        let d = f64::from(v) - f64::from(w);
        d * d
    });
    Ok((sum / points_a.len() as f64).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_is_zero_and_order_invariant() {
        let a = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 2.0, 0.0]];
        let v = [0.1, 0.2, 0.3];
        assert_eq!(nearest_value_error(&a, &v, &a, &v).unwrap(), 0.0);
        let b = [[0.0, 2.1, 0.0], [0.0, 0.1, 0.0]];
        let w = [0.0, 0.5];
        let e1 = nearest_value_error(&a, &v, &b, &w).unwrap();
        let e2 = nearest_value_error(&[a[2], a[0], a[1]], &[v[2], v[0], v[1]], &b, &w).unwrap();
        assert!((e1 - e2).abs() < 1e-12);
        // a0 -> b1 (0.1 vs 0.5), a1 -> b1 (0.2 vs 0.5), a2 -> b0 (0.3 vs 0.0)
        let expected = ((0.16f64 + 0.09 + 0.09) / 3.0).sqrt();
        assert!((e1 - expected).abs() < 1e-6);
    }
}
