//! Eigen-decomposition of a symmetric 3×3 matrix, for the covariance analysis of thesis eq.
//! 5.1-5.2 (PCA normals and curvature, and the differentiable mean curvature of the losses).
//!
//! nalgebra's `SymmetricEigen` (Householder tridiagonalisation and implicit QR with Wilkinson
//! shifts, `f64`), the design card's dense linear algebra: on the 1-ring covariances of a noisy
//! 163 842-vertex sphere, the curvature hot loop's input, it took 2.9-3.0 µs per matrix against
//! 3.2-3.6 µs for the cyclic Jacobi rotations it replaced, with the same accuracy (largest
//! residual `|Ax − λx| / max|A|` 2.8e-15 vs 2.3e-15) and normals within 5e-8 rad (docs/io.md,
//! "Design-card crates", has the command). Zero and non-finite matrices never reach the
//! iteration: every vector is an eigenvector of zero, and NaN has no decomposition to find.

use nalgebra::Matrix3;

/// Iteration cap: a finite symmetric 3×3 converges in a handful of QR sweeps.
const MAX_ITERATIONS: usize = 64;

/// Eigenvalues ascending and the matching unit eigenvectors (`vectors[i]` for `values[i]`) of
/// the symmetric matrix `a` (only its upper triangle is read). Public so that differentiable
/// versions of eq. 5.2 (the losses crate) take the same eigenvectors as the metrics. A zero or
/// non-finite `a` gives its diagonal and the coordinate axes.
///
/// ```
/// use meshgnn_geometry::symmetric_eigen3;
/// let (values, vectors) = symmetric_eigen3([[2.0, 1.0, 0.0], [1.0, 2.0, 0.0], [0.0, 0.0, 5.0]]);
/// assert!((values[0] - 1.0).abs() < 1e-12 && (values[1] - 3.0).abs() < 1e-12);
/// assert!((vectors[0][0] + vectors[0][1]).abs() < 1e-12 && vectors[0][2].abs() < 1e-12);
/// ```
pub fn symmetric_eigen3(a: [[f64; 3]; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
    let axes = (
        [a[0][0], a[1][1], a[2][2]],
        [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
    );
    let m = Matrix3::new(
        a[0][0], a[0][1], a[0][2], //
        a[0][1], a[1][1], a[1][2], //
        a[0][2], a[1][2], a[2][2],
    );
    let scale = m.iter().fold(0.0f64, |s, x| s.max(x.abs()));
    let (values, vectors) = if scale > 0.0 && scale.is_finite() {
        match m.try_symmetric_eigen(f64::EPSILON, MAX_ITERATIONS) {
            Some(e) => (
                [0, 1, 2].map(|i| e.eigenvalues[i]),
                [0, 1, 2].map(|i| [0, 1, 2].map(|r| e.eigenvectors[(r, i)])),
            ),
            None => axes,
        }
    } else {
        axes
    };
    let mut order = [0usize, 1, 2];
    order.sort_by(|&i, &j| values[i].total_cmp(&values[j]));
    (order.map(|i| values[i]), order.map(|i| vectors[i]))
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
