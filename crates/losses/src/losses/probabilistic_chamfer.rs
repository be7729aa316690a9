//! Probabilistic Chamfer distance (thesis eq. 6.8), the point sampler's training loss.

use crate::Result;
use crate::losses::tensor_points::{
    check_vector, nearest_index_tensor, points_of, row_squared_distances,
};
use candle_core::Tensor;

/// Eq. 6.8: `mean_{y∈P_s} p(y) min_{x∈P̂} ‖x − y‖² + mean_{x∈P̂} p(NN(x, P_s)) min_{y∈P_s}
/// ‖x − y‖²` for points `surface: (N, 3)` sampled from the input surface, the sampler's points
/// `sampled: (M, 3)` and their inclusion probabilities `probabilities: (M)`. In the second
/// term `p(y)` is the probability of the sampled point nearest to `x`. Sums are divided by the
/// counts like [`super::chamfer_loss`]. Differentiable in the probabilities (the thesis' use)
/// and in both point sets.
///
/// ```
/// use candle_core::{Device, Tensor};
/// use meshgnn_losses::losses::probabilistic_chamfer;
/// let d = Device::Cpu;
/// let surface = Tensor::new(&[[0.0f32, 0.0, 0.0], [2.0, 0.0, 0.0]], &d)?;
/// let sampled = Tensor::new(&[[0.0f32, 0.0, 1.0]], &d)?;
/// let p = Tensor::new(&[0.5f32], &d)?;
/// // first: 0.5 · 1; second: (0.5 · 1 + 0.5 · 5) / 2
/// assert_eq!(probabilistic_chamfer(&surface, &sampled, &p)?.to_scalar::<f32>()?, 2.0);
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn probabilistic_chamfer(
    surface: &Tensor,
    sampled: &Tensor,
    probabilities: &Tensor,
) -> Result<Tensor> {
    let s = points_of("surface points", surface)?;
    let y = points_of("sampled points", sampled)?;
    check_vector("sample probabilities", probabilities, y.len())?;
    let device = surface.device();
    let y_to_s = nearest_index_tensor(&y, &s, device)?;
    let s_to_y = nearest_index_tensor(&s, &y, device)?;
    let first = row_squared_distances(sampled, &surface.index_select(&y_to_s, 0)?)?
        .mul(probabilities)?
        .mean_all()?;
    let second = row_squared_distances(surface, &sampled.index_select(&s_to_y, 0)?)?
        .mul(&probabilities.index_select(&s_to_y, 0)?)?
        .mean_all()?;
    Ok(first.add(&second)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::losses::gradient_check::assert_gradient_matches;
    use candle_core::Device;

    #[test]
    fn finite_difference_gradients() {
        let dev = Device::Cpu;
        let surface = Tensor::new(
            &[
                [0.0f64, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [1.0, 1.0, 0.2],
            ],
            &dev,
        )
        .unwrap();
        let sampled = Tensor::new(&[[0.1f64, 0.1, 0.1], [0.9, 0.8, 0.0]], &dev).unwrap();
        let p = Tensor::new(&[0.3f64, 0.8], &dev).unwrap();
        assert_gradient_matches(&p, |p| probabilistic_chamfer(&surface, &sampled, p), 1e-6);
        assert_gradient_matches(&sampled, |y| probabilistic_chamfer(&surface, y, &p), 1e-6);
    }

    #[test]
    fn zero_probability_costs_nothing() {
        let dev = Device::Cpu;
        let surface = Tensor::new(&[[0.0f32, 0.0, 0.0]], &dev).unwrap();
        let sampled = Tensor::new(&[[3.0f32, 0.0, 0.0]], &dev).unwrap();
        let p = Tensor::new(&[0.0f32], &dev).unwrap();
        let l = probabilistic_chamfer(&surface, &sampled, &p).unwrap();
        assert_eq!(l.to_scalar::<f32>().unwrap(), 0.0);
        assert!(probabilistic_chamfer(&surface, &sampled, &p.reshape((1, 1)).unwrap()).is_err());
    }
}
