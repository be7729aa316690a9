//! Temporal coherence loss `L_c` of thesis eq. 4.2 (after Cudeiro et al., "Capture, Learning,
//! and Synthesis of 3D Speaking Styles", CVPR 2019).

use crate::{Error, Result};
use candle_core::Tensor;

/// Eq. 4.2, `L_c = ‖(x̂_t − x̂_{t−1}) − (x_t − x_{t−1})‖₁`, averaged over all elements and all
/// `T − 1` consecutive frame pairs. `predicted`, `target`: `(T, V, 3)` or `(B, T, V, 3)`; the
/// time axis is the third from last. Fails for fewer than two frames.
///
/// ```
/// use candle_core::{Device, Tensor};
/// use meshgnn_losses::losses::temporal_coherence;
/// // one vertex, two frames: predicted moves by 1 in x, target by 3 → |1 − 3| / 3 coordinates
/// let p = Tensor::new(&[[[0.0f32, 0.0, 0.0]], [[1.0, 0.0, 0.0]]], &Device::Cpu)?;
/// let t = Tensor::new(&[[[0.0f32, 0.0, 0.0]], [[3.0, 0.0, 0.0]]], &Device::Cpu)?;
/// let l = temporal_coherence(&p, &t)?.to_scalar::<f32>()?;
/// assert!((l - 2.0 / 3.0).abs() < 1e-6);
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn temporal_coherence(predicted: &Tensor, target: &Tensor) -> Result<Tensor> {
    let dims = predicted.dims();
    if target.dims() != dims {
        return Err(Error::Shape {
            what: "target",
            expected: "the shape of the prediction",
            actual: target.dims().to_vec(),
        });
    }
    if !(dims.len() == 3 || dims.len() == 4) || dims.last() != Some(&3) {
        return Err(Error::Shape {
            what: "prediction",
            expected: "(T, V, 3) or (B, T, V, 3)",
            actual: dims.to_vec(),
        });
    }
    let time = dims.len() - 3;
    let frames = dims.get(time).copied().unwrap_or(0);
    if frames < 2 {
        return Err(Error::InvalidParameter {
            name: "frames",
            message: format!("temporal coherence needs at least 2 frames, got {frames}"),
        });
    }
    let velocity = |x: &Tensor| -> Result<Tensor> {
        Ok(x.narrow(time, 1, frames - 1)?
            .sub(&x.narrow(time, 0, frames - 1)?)?)
    };
    Ok(velocity(predicted)?
        .sub(&velocity(target)?)?
        .abs()?
        .mean_all()?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::losses::gradient_check::assert_gradient_matches;
    use candle_core::Device;

    #[test]
    fn constant_offset_costs_nothing() {
        // a prediction offset by a constant in every frame has the target's velocity
        let t = Tensor::new(
            &[[[0.0f32, 1.0, 2.0]], [[1.0, 1.5, 2.0]], [[3.0, 0.0, 1.0]]],
            &Device::Cpu,
        )
        .unwrap();
        let p = t.affine(1.0, 0.25).unwrap();
        let l = temporal_coherence(&p, &t)
            .unwrap()
            .to_scalar::<f32>()
            .unwrap();
        assert!(l.abs() < 1e-6);
        assert!(
            temporal_coherence(&t.narrow(0, 0, 1).unwrap(), &t.narrow(0, 0, 1).unwrap()).is_err()
        );
    }

    #[test]
    fn finite_difference_gradient_batched() {
        let dev = Device::Cpu;
        let target = Tensor::new(
            &[[[[0.1f64, 0.2, 0.3]], [[0.5, -0.1, 0.0]], [[0.9, 0.3, -0.2]]]],
            &dev,
        )
        .unwrap();
        let x = Tensor::new(
            &[[[[0.0f64, 0.1, 0.4]], [[0.3, 0.2, 0.15]], [[0.4, 0.8, -0.6]]]],
            &dev,
        )
        .unwrap();
        assert_gradient_matches(&x, |x| temporal_coherence(x, &target), 1e-6);
    }
}
