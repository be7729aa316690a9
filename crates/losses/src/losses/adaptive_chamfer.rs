//! Adaptive Chamfer distance (thesis eq. 5.7) and its curvature weights.

use crate::losses::chamfer_loss::directed_squared_distances;
use crate::losses::tensor_points::check_vector;
use crate::validate::check_scalars;
use crate::{Error, Result};
use candle_core::Tensor;

/// The weights `w_K̄(x)` of eq. 5.7 for `mean_curvature: #P1` (eq. 5.3): `sigmoid((K̄(x) /
/// mean K̄) / τ)` with temperature `tau` (τ = 10 in the thesis, footnote to eq. 5.7).
///
/// "Normalised curvature" is the curvature divided by the cloud's mean curvature: flat points
/// get ≈ 0 and weight 0.5, sharp points get tens and a weight approaching 1, so salient points
/// count up to twice as much; the division makes the weights invariant to the curvature's
/// scale. A cloud with zero mean curvature (a plane) gets uniform weights 0.5.
///
/// ```
/// use meshgnn_losses::losses::adaptive_chamfer_weights;
/// let w = adaptive_chamfer_weights(&[0.0, 0.0, 0.0, 40.0], 10.0)?; // mean 10
/// assert_eq!(w[0], 0.5);
/// assert!((w[3] - 1.0 / (1.0 + (-0.4f32).exp())).abs() < 1e-6); // sigmoid(4 / 10)
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn adaptive_chamfer_weights(mean_curvature: &[f32], tau: f32) -> Result<Vec<f32>> {
    if !(tau.is_finite() && tau > 0.0) {
        return Err(Error::InvalidParameter {
            name: "tau",
            message: format!("the temperature must be positive and finite, got {tau}"),
        });
    }
    if mean_curvature.is_empty() {
        return Err(Error::Empty {
            what: "mean curvatures",
        });
    }
    check_scalars("mean curvatures", mean_curvature)?;
    let mean =
        mean_curvature.iter().map(|&k| f64::from(k)).sum::<f64>() / mean_curvature.len() as f64;
    Ok(mean_curvature
        .iter()
        .map(|&k| {
            let z = if mean > 0.0 { f64::from(k) / mean } else { 0.0 };
            (1.0 / (1.0 + (-z / f64::from(tau)).exp())) as f32
        })
        .collect())
}

/// Eq. 5.7: `mean_{x∈P1} w(x) min_{y∈P2} ‖x − y‖² + mean_{y∈P2} min_{x∈P1} ‖x − y‖²` for the
/// original `p1: (N, 3)`, simplified `p2: (M, 3)` and `weights: (N)` (e.g. from
/// [`adaptive_chamfer_weights`]); only the first term is weighted, as in the thesis. Sums are
/// divided by the point counts like [`super::chamfer_loss`].
///
/// ```
/// use candle_core::{Device, Tensor};
/// use meshgnn_losses::losses::adaptive_chamfer;
/// let a = Tensor::new(&[[0.0f32, 0.0, 0.0], [2.0, 0.0, 0.0]], &Device::Cpu)?;
/// let b = Tensor::new(&[[0.0f32, 0.0, 0.0]], &Device::Cpu)?;
/// let w = Tensor::new(&[1.0f32, 0.5], &Device::Cpu)?;
/// assert_eq!(adaptive_chamfer(&a, &b, &w)?.to_scalar::<f32>()?, 1.0); // (0 + 0.5·4) / 2
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn adaptive_chamfer(p1: &Tensor, p2: &Tensor, weights: &Tensor) -> Result<Tensor> {
    check_vector(
        "adaptive Chamfer weights",
        weights,
        p1.dims().first().copied().unwrap_or(0),
    )?;
    let forward = directed_squared_distances(p1, p2)?
        .mul(weights)?
        .mean_all()?;
    let reverse = directed_squared_distances(p2, p1)?.mean_all()?;
    Ok(forward.add(&reverse)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::losses::gradient_check::assert_gradient_matches;
    use candle_core::Device;

    #[test]
    fn weights_reject_bad_tau_and_are_uniform_on_planes() {
        assert!(adaptive_chamfer_weights(&[0.1], 0.0).is_err());
        assert_eq!(
            adaptive_chamfer_weights(&[0.0, 0.0], 10.0).unwrap(),
            vec![0.5, 0.5]
        );
    }

    #[test]
    fn finite_difference_gradient() {
        let dev = Device::Cpu;
        let p1 = Tensor::new(
            &[[0.0f64, 0.0, 0.0], [1.0, 0.2, 0.1], [0.3, 0.9, 0.5]],
            &dev,
        )
        .unwrap();
        let w = Tensor::new(&[0.9f64, 0.5, 0.7], &dev).unwrap();
        let x = Tensor::new(&[[0.1f64, 0.2, 0.0], [0.8, 0.1, 0.3]], &dev).unwrap();
        assert_gradient_matches(&x, |x| adaptive_chamfer(&p1, x, &w), 1e-6);
        assert_gradient_matches(&p1, |p| adaptive_chamfer(p, &x, &w), 1e-6);
    }
}
