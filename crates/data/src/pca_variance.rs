//! Explained-variance curve of PCA over a set of registered shapes — the compactness measure of
//! thesis ch. 3 (eq. 3.2 PCA model) used here to show that articulation makes the hand space
//! non-linear (a pose-free set needs far fewer components for the same variance).
//!
//! With `n` shapes of `3·#V` coordinates and `n ≪ 3·#V`, the non-zero eigenvalues of the
//! covariance equal those of the `n×n` Gram matrix `X Xᵀ / (n − 1)` of the centred data, so the
//! eigen-solve is O(n³) (faer's self-adjoint eigen-decomposition) after an O(n²·#V) product.

use faer::{Mat, Side};
use rayon::prelude::*;

use crate::error::{Error, Result, invalid};

/// Cumulative explained variance of PCA over `shapes: n × #V×3` (every shape the same `#V`):
/// entry `k` is the fraction of total variance captured by the first `k + 1` components;
/// `n − 1` entries (a centred set of `n` shapes has rank ≤ `n − 1`).
///
/// ```
/// use meshgnn_data::pca_explained_variance;
/// // Three shapes on a line in shape space: one component explains everything.
/// let a = vec![[0.0f32, 0.0, 0.0]; 2];
/// let b = vec![[1.0f32, 0.0, 0.0]; 2];
/// let c = vec![[2.0f32, 0.0, 0.0]; 2];
/// let curve = pca_explained_variance(&[a, b, c])?;
/// assert!((curve[0] - 1.0).abs() < 1e-12);
/// # Ok::<(), meshgnn_data::Error>(())
/// ```
pub fn pca_explained_variance(shapes: &[Vec<[f32; 3]>]) -> Result<Vec<f64>> {
    let n = shapes.len();
    if n < 2 {
        return Err(invalid("shapes", n, "PCA needs at least two shapes"));
    }
    let v = shapes[0].len();
    if let Some((i, s)) = shapes.iter().enumerate().find(|(_, s)| s.len() != v) {
        return Err(Error::Topology {
            element: format!("shape {i}"),
            message: format!("has {} vertices, shape 0 has {v}", s.len()),
        });
    }
    let mut mean = vec![0.0f64; 3 * v];
    for s in shapes {
        for (m, c) in mean.iter_mut().zip(s.iter().flatten()) {
            *m += f64::from(*c);
        }
    }
    mean.iter_mut().for_each(|m| *m /= n as f64);
    let centred: Vec<Vec<f64>> = shapes
        .par_iter()
        .map(|s| {
            s.iter()
                .flatten()
                .zip(&mean)
                .map(|(c, m)| f64::from(*c) - m)
                .collect()
        })
        .collect();
    let gram: Vec<f64> = (0..n * n)
        .into_par_iter()
        .map(|ij| {
            let (i, j) = (ij / n, ij % n);
            centred[i].iter().zip(&centred[j]).map(|(a, b)| a * b).sum()
        })
        .collect();
    let g = Mat::<f64>::from_fn(n, n, |i, j| gram[i * n + j]);
    let mut values = g
        .self_adjoint_eigenvalues(Side::Lower)
        .map_err(|e| invalid("shapes", n, &format!("eigen-decomposition failed: {e:?}")))?;
    values.iter_mut().for_each(|x| *x = x.max(0.0));
    values.sort_by(|a, b| b.total_cmp(a));
    let total: f64 = values.iter().sum();
    if total <= 0.0 {
        return Err(invalid(
            "shapes",
            n,
            "all shapes are identical (zero variance)",
        ));
    }
    let mut acc = 0.0;
    Ok(values
        .iter()
        .take(n - 1)
        .map(|x| {
            acc += x;
            acc / total
        })
        .collect())
}

/// Number of components needed to reach `fraction` of the variance on `curve` (from
/// [`pca_explained_variance`]); `curve.len()` when never reached.
///
/// ```
/// assert_eq!(meshgnn_data::components_for_variance(&[0.5, 0.9, 0.97, 1.0], 0.95), 3);
/// ```
pub fn components_for_variance(curve: &[f64], fraction: f64) -> usize {
    curve
        .iter()
        .position(|&c| c >= fraction)
        .map_or(curve.len(), |i| i + 1)
}
