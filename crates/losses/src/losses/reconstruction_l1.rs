//! Reconstruction loss `L_r` of thesis eq. 4.2 (also the L1 training loss of ch. 3).

use crate::{Error, Result};
use candle_core::Tensor;

/// Eq. 4.2, `L_r = ‖x̂ − x‖₁`, averaged over all elements (`mean |x̂ − x|`, the convention of
/// PyTorch's `l1_loss` used by the thesis' code, so the scale does not grow with the mesh).
/// `predicted`, `target`: any equal shapes, e.g. `(B, V, 3)`.
///
/// ```
/// use candle_core::{Device, Tensor};
/// use meshgnn_losses::losses::reconstruction_l1;
/// let a = Tensor::new(&[[0.0f32, 1.0, 2.0]], &Device::Cpu)?;
/// let b = Tensor::new(&[[1.0f32, 1.0, 0.0]], &Device::Cpu)?;
/// assert_eq!(reconstruction_l1(&a, &b)?.to_scalar::<f32>()?, 1.0); // (1 + 0 + 2) / 3
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn reconstruction_l1(predicted: &Tensor, target: &Tensor) -> Result<Tensor> {
    if predicted.dims() != target.dims() {
        return Err(Error::Shape {
            what: "target",
            expected: "the shape of the prediction",
            actual: target.dims().to_vec(),
        });
    }
    if predicted.elem_count() == 0 {
        return Err(Error::Empty { what: "prediction" });
    }
    Ok(predicted.sub(target)?.abs()?.mean_all()?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::losses::gradient_check::assert_gradient_matches;
    use candle_core::{DType, Device};

    #[test]
    fn zero_for_identical_and_shape_checked() {
        let a = Tensor::new(&[[0.5f32, -1.0, 2.0], [1.0, 2.0, 3.0]], &Device::Cpu).unwrap();
        assert_eq!(
            reconstruction_l1(&a, &a)
                .unwrap()
                .to_scalar::<f32>()
                .unwrap(),
            0.0
        );
        assert!(reconstruction_l1(&a, &a.narrow(0, 0, 1).unwrap()).is_err());
    }

    #[test]
    fn finite_difference_gradient() {
        let target = Tensor::new(&[[0.1f64, 0.7, -0.3], [0.0, 0.2, 0.4]], &Device::Cpu).unwrap();
        let x = Tensor::new(&[[0.5f64, 0.2, 0.1], [-0.4, 0.9, 0.0]], &Device::Cpu).unwrap();
        assert_gradient_matches(&x, |x| reconstruction_l1(x, &target), 1e-6);
        assert_eq!(x.dtype(), DType::F64);
    }
}
