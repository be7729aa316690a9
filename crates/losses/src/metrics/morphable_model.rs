//! Morphable-model metrics of thesis ch. 3.4.1 (after Styner et al. 2003 and Dai et al.
//! 2017): compactness, generalisation and specificity.

use crate::metrics::per_vertex_error::per_vertex_error;
use crate::validate::{check_len, check_points};
use crate::{Error, Result};
use faer::{Mat, Side};
use rayon::prelude::*;

/// Mean and standard deviation of per-shape errors (the error bars of thesis Figure 3.10).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorSummary {
    /// Mean over shapes of the mean per-vertex error (input units, e.g. mm).
    pub mean: f64,
    /// Population standard deviation over shapes.
    pub std: f64,
}

impl ErrorSummary {
    fn of(errors: &[f64]) -> Self {
        let n = errors.len().max(1) as f64;
        let mean = errors.iter().sum::<f64>() / n;
        let var = errors.iter().map(|e| (e - mean) * (e - mean)).sum::<f64>() / n;
        Self {
            mean,
            std: var.sqrt(),
        }
    }
}

/// PCA spectrum of a shape collection (thesis Figure 3.11).
#[derive(Clone, Debug, PartialEq)]
pub struct Compactness {
    /// Variance of each principal component, largest first (squared input units).
    pub variances: Vec<f64>,
    /// `cumulative[c]`: fraction (0-1) of the total variance explained by the first `c + 1`
    /// components — compactness as a function of the number of components.
    pub cumulative: Vec<f64>,
}

impl Compactness {
    /// How many components reach `fraction` (0-1) of the variance: the first `c` with
    /// `cumulative[c − 1] >= fraction`, or all of them when none does.
    ///
    /// ```
    /// use meshgnn_losses::metrics::Compactness;
    /// let c = Compactness { variances: vec![5.0, 4.0, 0.7, 0.3], cumulative: vec![0.5, 0.9, 0.97, 1.0] };
    /// assert_eq!((c.components_for(0.95), c.components_for(0.5), c.components_for(1.1)), (3, 1, 4));
    /// ```
    pub fn components_for(&self, fraction: f64) -> usize {
        self.cumulative
            .iter()
            .position(|&c| c >= fraction)
            .map_or(self.cumulative.len(), |i| i + 1)
    }
}

/// Checks a collection of registered shapes: non-empty, same vertex count, finite.
fn check_shapes(what: &'static str, shapes: &[Vec<[f32; 3]>]) -> Result<usize> {
    let first = shapes.first().ok_or(Error::Empty { what })?;
    for s in shapes {
        check_points(what, s)?;
        check_len(what, first.len(), s.len())?;
    }
    Ok(first.len())
}

/// Registered shapes centred on their mean, with their `S×S` Gram matrix: the common start of
/// PCA (eq. 3.2) and compactness, which take the spectrum from the Gram matrix instead of the
/// `3V×3V` covariance.
#[derive(Clone, Debug)]
pub struct CentredShapes {
    /// Mean shape, `3V` (x, y, z per vertex).
    pub mean: Vec<f64>,
    /// Each shape minus the mean, `S × 3V`.
    pub centred: Vec<Vec<f64>>,
    /// `X Xᵀ / (S − 1)` of the centred shapes `X`, `S×S`; its eigenvalues are the PCA variances.
    pub gram: Mat<f64>,
}

/// Centres `S ≥ 2` registered shapes (each `#V×3`) in `f64` and forms their Gram matrix
/// (O(S²·V), rows in parallel, a fixed summation order so any thread count gives the same bits).
///
/// ```
/// use meshgnn_losses::metrics::centred_shapes;
/// let shapes = vec![vec![[0.0, 0.0, 0.0]], vec![[2.0, 0.0, 0.0]]];
/// let c = centred_shapes(&shapes)?;
/// assert_eq!(c.mean, vec![1.0, 0.0, 0.0]);
/// assert_eq!(c.gram[(0, 1)], -1.0); // (-1)·(+1) / (2 − 1)
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn centred_shapes(shapes: &[Vec<[f32; 3]>]) -> Result<CentredShapes> {
    let v = check_shapes("training shapes", shapes)?;
    let s = shapes.len();
    if s < 2 {
        return Err(Error::InvalidParameter {
            name: "shapes",
            message: format!("needs at least two shapes, got {s}"),
        });
    }
    let mean: Vec<f64> = (0..3 * v)
        .into_par_iter()
        .map(|d| {
            shapes
                .iter()
                .map(|x| x.get(d / 3).map_or(0.0, |p| f64::from(p[d % 3])))
                .sum::<f64>()
                / s as f64
        })
        .collect();
    let centred: Vec<Vec<f64>> = shapes
        .par_iter()
        .map(|x| {
            x.iter()
                .flat_map(|p| p.iter().map(|&c| f64::from(c)))
                .zip(&mean)
                .map(|(c, m)| c - m)
                .collect()
        })
        .collect();
    // Lower triangle, one row per task; the product is symmetric term by term.
    let rows: Vec<Vec<f64>> = centred
        .par_iter()
        .enumerate()
        .map(|(i, a)| {
            centred
                .iter()
                .take(i + 1)
                .map(|b| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>())
                .collect()
        })
        .collect();
    let denom = (s - 1) as f64;
    let gram = Mat::from_fn(s, s, |i, j| {
        let (r, c) = if j <= i { (i, j) } else { (j, i) };
        rows.get(r)
            .and_then(|row| row.get(c))
            .copied()
            .unwrap_or(0.0)
            / denom
    });
    Ok(CentredShapes {
        mean,
        centred,
        gram,
    })
}

/// Compactness: the PCA variances of `shapes` (`S` registered shapes, each `#V×3`) and the
/// cumulative fraction of variance they explain. Computed from the `S×S` Gram matrix of the
/// centred shapes in `f64` (exact PCA spectrum, O(S²·V)); at most `S − 1` components.
///
/// ```
/// use meshgnn_losses::metrics::compactness;
/// // three shapes that differ only along x: one component explains everything
/// let shapes = vec![vec![[0.0, 0.0, 0.0]], vec![[1.0, 0.0, 0.0]], vec![[2.0, 0.0, 0.0]]];
/// let c = compactness(&shapes)?;
/// assert!((c.variances[0] - 1.0).abs() < 1e-12); // variance of {0, 1, 2}
/// assert!((c.cumulative[0] - 1.0).abs() < 1e-12);
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn compactness(shapes: &[Vec<[f32; 3]>]) -> Result<Compactness> {
    let s = shapes.len();
    let gram = centred_shapes(shapes)?.gram;
    let mut variances =
        gram.self_adjoint_eigenvalues(Side::Lower)
            .map_err(|e| Error::InvalidParameter {
                name: "shapes",
                message: format!("eigen-decomposition of the Gram matrix failed: {e:?}"),
            })?;
    variances.reverse();
    variances.truncate(s - 1);
    for x in &mut variances {
        *x = x.max(0.0);
    }
    let total: f64 = variances.iter().sum();
    let mut acc = 0.0;
    let cumulative = variances
        .iter()
        .map(|x| {
            acc += x;
            if total > 0.0 { acc / total } else { 1.0 }
        })
        .collect();
    Ok(Compactness {
        variances,
        cumulative,
    })
}

/// Generalisation (ch. 3.4.1): the per-vertex error (mean Euclidean distance, input units)
/// between each held-out shape of `test_shapes` (`#V×3` each) and the model's reconstruction
/// `reconstruct(shape)` (encode + decode, or PCA projection), summarised over shapes.
///
/// ```
/// use meshgnn_losses::metrics::generalisation;
/// let test = vec![vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]];
/// // a "model" that shifts every vertex by 0.5 in z
/// let g = generalisation(&test, |s| Ok(s.iter().map(|p| [p[0], p[1], p[2] + 0.5]).collect()))?;
/// assert!((g.mean - 0.5).abs() < 1e-7);
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn generalisation<F>(test_shapes: &[Vec<[f32; 3]>], reconstruct: F) -> Result<ErrorSummary>
where
    F: Fn(&[[f32; 3]]) -> Result<Vec<[f32; 3]>> + Sync,
{
    check_shapes("test shapes", test_shapes)?;
    let errors = test_shapes
        .par_iter()
        .map(|s| per_vertex_error(&reconstruct(s)?, s))
        .collect::<Result<Vec<f64>>>()?;
    Ok(ErrorSummary::of(&errors))
}

/// Specificity (ch. 3.4.1): for each of the model's random `samples` (`#V×3` each; the
/// thesis draws 1000 with a seeded sampler), the per-vertex error to its closest shape in
/// `training`; summarised over samples (input units).
///
/// ```
/// use meshgnn_losses::metrics::specificity;
/// let training = vec![vec![[0.0, 0.0, 0.0]], vec![[10.0, 0.0, 0.0]]];
/// let samples = vec![vec![[1.0, 0.0, 0.0]], vec![[7.0, 0.0, 0.0]]];
/// let s = specificity(&samples, &training)?;
/// assert_eq!(s.mean, 2.0); // closest distances 1 and 3
/// assert_eq!(s.std, 1.0);
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn specificity(samples: &[Vec<[f32; 3]>], training: &[Vec<[f32; 3]>]) -> Result<ErrorSummary> {
    let v = check_shapes("model samples", samples)?;
    check_len(
        "vertices of the training shapes",
        v,
        check_shapes("training shapes", training)?,
    )?;
    let errors = samples
        .par_iter()
        .map(|s| {
            training
                .iter()
                .map(|t| per_vertex_error(s, t))
                .try_fold(f64::INFINITY, |best, e| e.map(|e| best.min(e)))
        })
        .collect::<Result<Vec<f64>>>()?;
    Ok(ErrorSummary::of(&errors))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compactness_of_two_independent_directions() {
        // 4 one-vertex shapes at (±2, 0, 0) and (0, ±1, 0): variances 8/3 and 2/3.
        let shapes = vec![
            vec![[2.0, 0.0, 0.0]],
            vec![[-2.0, 0.0, 0.0]],
            vec![[0.0, 1.0, 0.0]],
            vec![[0.0, -1.0, 0.0]],
        ];
        let c = compactness(&shapes).unwrap();
        assert_eq!(c.variances.len(), 3);
        assert!((c.variances[0] - 8.0 / 3.0).abs() < 1e-12);
        assert!((c.variances[1] - 2.0 / 3.0).abs() < 1e-12);
        assert!(c.variances[2].abs() < 1e-12);
        assert!((c.cumulative[0] - 0.8).abs() < 1e-12);
        assert!((c.cumulative[2] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn perfect_model_generalises_with_zero_error() {
        let test = vec![vec![[0.0, 1.0, 2.0]; 4], vec![[3.0, 1.0, 2.0]; 4]];
        let g = generalisation(&test, |s| Ok(s.to_vec())).unwrap();
        assert_eq!(
            g,
            ErrorSummary {
                mean: 0.0,
                std: 0.0
            }
        );
        let s = specificity(&test, &test).unwrap();
        assert_eq!(s.mean, 0.0);
    }

    #[test]
    fn mismatched_vertex_counts_are_rejected() {
        let a = vec![vec![[0.0f32; 3]; 3]];
        let b = vec![vec![[0.0f32; 3]; 2]];
        assert!(specificity(&a, &b).is_err());
        assert!(generalisation(&a, |_| Ok(vec![[0.0; 3]; 2])).is_err());
    }
}
