//! Eigen-decomposition of a symmetric 3×3 matrix by cyclic Jacobi rotations in `f64`: robust
//! for repeated and zero eigenvalues (flat or isotropic neighbourhoods), where closed-form
//! cubic solutions lose accuracy. Used by the covariance analysis of thesis eq. 5.1-5.2.

/// Eigenvalues ascending and the matching unit eigenvectors (`vectors[i]` for `values[i]`) of
/// the symmetric matrix `a` (only its upper triangle is read). Public so that differentiable
/// versions of eq. 5.2 (the losses crate) take the same eigenvectors as the metrics.
///
/// ```
/// use meshgnn_geometry::symmetric_eigen3;
/// let (values, vectors) = symmetric_eigen3([[2.0, 1.0, 0.0], [1.0, 2.0, 0.0], [0.0, 0.0, 5.0]]);
/// assert!((values[0] - 1.0).abs() < 1e-12 && (values[1] - 3.0).abs() < 1e-12);
/// assert!((vectors[0][0] + vectors[0][1]).abs() < 1e-12 && vectors[0][2].abs() < 1e-12);
/// ```
pub fn symmetric_eigen3(a: [[f64; 3]; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
    let mut m = [
        [a[0][0], a[0][1], a[0][2]],
        [a[0][1], a[1][1], a[1][2]],
        [a[0][2], a[1][2], a[2][2]],
    ];
    // Columns of v are the eigenvectors.
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let scale = m.iter().flatten().fold(0.0f64, |s, x| s.max(x.abs()));
    if scale > 0.0 && scale.is_finite() {
        for _sweep in 0..32 {
            let off = m[0][1].abs() + m[0][2].abs() + m[1][2].abs();
            if off <= 1e-300 || off <= f64::EPSILON * 1e-3 * scale {
                break;
            }
            for (p, q) in [(0, 1), (0, 2), (1, 2)] {
                if m[p][q] == 0.0 {
                    continue;
                }
                let theta = (m[q][q] - m[p][p]) / (2.0 * m[p][q]);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                // m ← Jᵀ m J with the rotation J in the (p, q) plane.
                for row in &mut m {
                    let (mkp, mkq) = (row[p], row[q]);
                    row[p] = c * mkp - s * mkq;
                    row[q] = s * mkp + c * mkq;
                }
                let (rp, rq) = (m[p], m[q]);
                m[p] = [0, 1, 2].map(|k| c * rp[k] - s * rq[k]);
                m[q] = [0, 1, 2].map(|k| s * rp[k] + c * rq[k]);
                for row in &mut v {
                    let (vp, vq) = (row[p], row[q]);
                    row[p] = c * vp - s * vq;
                    row[q] = s * vp + c * vq;
                }
            }
        }
    }
    let mut order = [0usize, 1, 2];
    order.sort_by(|&i, &j| m[i][i].total_cmp(&m[j][j]));
    let values = order.map(|i| m[i][i]);
    let vectors = order.map(|i| [v[0][i], v[1][i], v[2][i]]);
    (values, vectors)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(a: [[f64; 3]; 3]) -> [f64; 3] {
        let (values, vectors) = symmetric_eigen3(a);
        assert!(values[0] <= values[1] && values[1] <= values[2]);
        for (lambda, x) in values.iter().zip(&vectors) {
            for r in 0..3 {
                let ax = (0..3).map(|c| a[r][c] * x[c]).sum::<f64>();
                assert!((ax - lambda * x[r]).abs() < 1e-12, "{a:?}");
            }
            let len = x.iter().map(|c| c * c).sum::<f64>();
            assert!((len - 1.0).abs() < 1e-12);
        }
        values
    }

    #[test]
    fn known_spectra() {
        let v = check([[2.0, 1.0, 0.0], [1.0, 2.0, 0.0], [0.0, 0.0, 5.0]]);
        assert!((v[0] - 1.0).abs() < 1e-14 && (v[1] - 3.0).abs() < 1e-14);
        // Rank one x xᵀ with x = (1, 2, 2): eigenvalues 0, 0, 9.
        let x = [1.0, 2.0, 2.0];
        let v = check([0, 1, 2].map(|r| [0, 1, 2].map(|c| x[r] * x[c])));
        assert!(v[0].abs() < 1e-14 && v[1].abs() < 1e-14 && (v[2] - 9.0).abs() < 1e-13);
        assert_eq!(check([[0.0; 3]; 3]), [0.0; 3]);
        check([[1e-8, 3e-9, -2e-9], [3e-9, 4e-8, 1e-9], [-2e-9, 1e-9, 2e-9]]);
    }
}
