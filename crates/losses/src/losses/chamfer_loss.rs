//! Differentiable Chamfer distance (thesis eq. 5.6) and its directed terms.

use crate::Result;
use crate::losses::tensor_points::{nearest_index_tensor, points_of, row_squared_distances};
use candle_core::Tensor;

/// Per-point squared distance `(N)` from each row of `from: (N, 3)` to its nearest row of
/// `to: (M, 3)`; the correspondence is found on detached values (`SpatialIndex`) and gathered with
/// `index_select`, so the result is differentiable in both point sets.
pub(crate) fn directed_squared_distances(from: &Tensor, to: &Tensor) -> Result<Tensor> {
    let a = points_of("first points", from)?;
    let b = points_of("second points", to)?;
    let nn = nearest_index_tensor(&a, &b, from.device())?;
    row_squared_distances(from, &to.index_select(&nn, 0)?)
}

/// Eq. 5.6 as a loss: `mean_{x∈P1} min_{y∈P2} ‖x − y‖² + mean_{y∈P2} min_{x∈P1} ‖x − y‖²`
/// for `p1: (N, 3)`, `p2: (M, 3)` (any float dtype). Eq. 5.6 writes sums; each term is divided
/// by its point count so the loss does not scale with the sampling density (the gradient only
/// changes by a constant factor per term).
///
/// ```
/// use candle_core::{Device, Tensor};
/// use meshgnn_losses::losses::chamfer_loss;
/// let a = Tensor::new(&[[0.0f32, 0.0, 0.0], [2.0, 0.0, 0.0]], &Device::Cpu)?;
/// let b = Tensor::new(&[[0.0f32, 0.0, 0.0]], &Device::Cpu)?;
/// assert_eq!(chamfer_loss(&a, &b)?.to_scalar::<f32>()?, 2.0); // (0 + 4) / 2 + 0
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn chamfer_loss(p1: &Tensor, p2: &Tensor) -> Result<Tensor> {
    let forward = directed_squared_distances(p1, p2)?.mean_all()?;
    let reverse = directed_squared_distances(p2, p1)?.mean_all()?;
    Ok(forward.add(&reverse)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::losses::gradient_check::assert_gradient_matches;
    use crate::metrics::chamfer_distance;
    use candle_core::Device;

    #[test]
    fn agrees_with_the_metric() {
        let a = [
            [0.0f32, 0.0, 0.0],
            [1.0, 0.5, 0.0],
            [0.3, 0.2, 0.9],
            [0.7, 0.1, 0.4],
        ];
        let b = [[0.1f32, 0.0, 0.0], [1.0, 1.0, 1.0], [0.5, 0.5, 0.5]];
        let ta = Tensor::new(&a, &Device::Cpu).unwrap();
        let tb = Tensor::new(&b, &Device::Cpu).unwrap();
        let loss = chamfer_loss(&ta, &tb).unwrap().to_scalar::<f32>().unwrap();
        let metric = chamfer_distance(&a, &b).unwrap().symmetric_mean();
        assert!((f64::from(loss) - metric).abs() < 1e-6);
        let same = chamfer_loss(&ta, &ta).unwrap().to_scalar::<f32>().unwrap();
        assert_eq!(same, 0.0);
    }

    #[test]
    fn finite_difference_gradient() {
        let dev = Device::Cpu;
        let target = Tensor::new(
            &[[0.0f64, 0.0, 0.0], [1.0, 0.2, 0.1], [0.3, 0.9, 0.5]],
            &dev,
        )
        .unwrap();
        let x = Tensor::new(&[[0.1f64, 0.2, 0.0], [0.8, 0.1, 0.3]], &dev).unwrap();
        assert_gradient_matches(&x, |x| chamfer_loss(x, &target), 1e-6);
        assert_gradient_matches(&x, |x| chamfer_loss(&target, x), 1e-6);
    }
}
