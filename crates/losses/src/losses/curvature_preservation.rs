//! Curvature preservation loss (thesis eq. 5.8, CE as a training term of eq. 5.9).

use crate::Result;
use crate::losses::tensor_points::{check_vector, nearest_index_tensor, points_of};
use candle_core::Tensor;

/// Eq. 5.8: `( mean_{x∈P1} (K̄_1(x) − K̄_2(NN(x, P2)))² )^{1/2}` for `p1: (N, 3)` with mean
/// curvatures `k1: (N)` and `p2: (M, 3)` with `k2: (M)`. Differentiable in `k1` and `k2` (the
/// simplifier's curvatures are gathered from the input cloud by the selection, so gradients
/// reach the selection scores); the nearest-neighbour map is fixed. The square root has an
/// infinite derivative at 0, so callers train with it only while the error is positive
/// (as the thesis does) or use its square.
///
/// ```
/// use candle_core::{Device, Tensor};
/// use meshgnn_losses::losses::curvature_preservation;
/// let d = Device::Cpu;
/// let p1 = Tensor::new(&[[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0]], &d)?;
/// let p2 = Tensor::new(&[[0.0f32, 0.0, 0.0]], &d)?;
/// let k1 = Tensor::new(&[0.1f32, 0.4], &d)?;
/// let k2 = Tensor::new(&[0.1f32], &d)?;
/// let ce = curvature_preservation(&p1, &k1, &p2, &k2)?.to_scalar::<f32>()?;
/// assert!((ce - (0.09f32 / 2.0).sqrt()).abs() < 1e-6);
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn curvature_preservation(
    p1: &Tensor,
    k1: &Tensor,
    p2: &Tensor,
    k2: &Tensor,
) -> Result<Tensor> {
    let a = points_of("original points", p1)?;
    let b = points_of("simplified points", p2)?;
    check_vector("original curvatures", k1, a.len())?;
    check_vector("simplified curvatures", k2, b.len())?;
    let nn = nearest_index_tensor(&a, &b, p1.device())?;
    Ok(k1
        .sub(&k2.index_select(&nn, 0)?)?
        .sqr()?
        .mean_all()?
        .sqrt()?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::losses::gradient_check::assert_gradient_matches;
    use crate::metrics::nearest_value_error;
    use candle_core::Device;

    #[test]
    fn agrees_with_the_metric_and_finite_differences() {
        let dev = Device::Cpu;
        let a = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let b = [[0.1f32, 0.0, 0.0], [0.0, 0.9, 0.0]];
        let (ka, kb) = ([0.05f32, 0.2, 0.1], [0.15f32, 0.0]);
        let p1 = Tensor::new(&a, &dev).unwrap();
        let p2 = Tensor::new(&b, &dev).unwrap();
        let t1 = Tensor::new(&ka, &dev).unwrap();
        let t2 = Tensor::new(&kb, &dev).unwrap();
        let loss = curvature_preservation(&p1, &t1, &p2, &t2)
            .unwrap()
            .to_scalar::<f32>()
            .unwrap();
        let metric = nearest_value_error(&a, &ka, &b, &kb).unwrap();
        assert!((f64::from(loss) - metric).abs() < 1e-6);

        let p1 = p1.to_dtype(candle_core::DType::F64).unwrap();
        let p2 = p2.to_dtype(candle_core::DType::F64).unwrap();
        let k1 = t1.to_dtype(candle_core::DType::F64).unwrap();
        let k2 = t2.to_dtype(candle_core::DType::F64).unwrap();
        assert_gradient_matches(&k2, |k| curvature_preservation(&p1, &k1, &p2, k), 1e-6);
        assert_gradient_matches(&k1, |k| curvature_preservation(&p1, k, &p2, &k2), 1e-6);
    }
}
