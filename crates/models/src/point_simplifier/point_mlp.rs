//! The point-wise layer of the projector network (thesis ch. 5.3.2 and 5.6): a shared
//! `Linear → BatchNorm → ReLU` applied to every point independently, after PointNet (Qi, Su, Mo
//! & Guibas 2017, "PointNet: Deep learning on point sets for 3D classification and
//! segmentation", CVPR).
//!
//! # Conventions
//! Features are `(N, C)`: one row per point. Batch normalisation takes its statistics over the
//! points of the cloud in training mode (`train = true`, updating the running mean and variance
//! with momentum 0.1) and uses the running statistics in evaluation mode, so inference on one
//! point does not depend on the others.

use candle_core::Tensor;
use candle_nn::{BatchNorm, Linear, Module, ModuleT, VarBuilder};

use super::fused_projector::HostAffine;
use crate::Result;

/// `x ↦ ReLU(BN(W x + b))` per point (ch. 5.6: "MLP followed by Batch Normalization and ReLU").
#[derive(Clone, Debug)]
pub struct PointMlp {
    linear: Linear,
    norm: BatchNorm,
}

impl PointMlp {
    /// A layer mapping `input` to `output` channels with parameters under `vb`
    /// (`linear.weight (output, input)`, `linear.bias`, `norm.{weight, bias, running_mean,
    /// running_var}`).
    ///
    /// ```
    /// use candle_core::{DType, Device, Tensor};
    /// use candle_nn::{VarBuilder, VarMap};
    /// use meshgnn_models::point_simplifier::PointMlp;
    /// let map = VarMap::new();
    /// let layer = PointMlp::new(VarBuilder::from_varmap(&map, DType::F32, &Device::Cpu), 3, 8)?;
    /// let y = layer.forward_t(&Tensor::zeros((5, 3), DType::F32, &Device::Cpu)?, false)?;
    /// assert_eq!(y.dims(), &[5, 8]);
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn new(vb: VarBuilder, input: usize, output: usize) -> Result<Self> {
        let linear = candle_nn::linear(input, output, vb.pp("linear"))?;
        let norm = candle_nn::batch_norm(output, 1e-5, vb.pp("norm"))?;
        Ok(Self { linear, norm })
    }

    /// From raw parts (tests, hand-set weights).
    pub fn from_parts(linear: Linear, norm: BatchNorm) -> Self {
        Self { linear, norm }
    }

    /// `features: (N, C_in)` → `(N, C_out)`; `train` selects batch statistics (and updates
    /// the running ones) or the running statistics. In evaluation the normalisation is folded
    /// into the linear map (`W' = diag(γ/σ) W`, `b' = (b − μ) γ/σ + β`): one matrix product
    /// and one bias pass instead of five passes over the `N × C` features.
    pub fn forward_t(&self, features: &Tensor, train: bool) -> Result<Tensor> {
        if train {
            let x = self.linear.forward(features)?;
            return Ok(self.norm.forward_t(&x, true)?.relu()?);
        }
        let (w, b) = self.folded()?;
        Ok(features.matmul(&w)?.broadcast_add(&b)?.relu()?)
    }

    /// The evaluation-mode map packed for the fused host projector.
    pub(crate) fn host_affine(&self) -> Result<HostAffine> {
        let (w, b) = self.folded()?;
        HostAffine::from_transposed(&w, Some(&b))
    }

    /// Whether the weights are trainable variables (autograd must see them).
    pub(crate) fn is_trainable(&self) -> bool {
        self.linear.weight().track_op()
    }

    /// The evaluation-mode affine map: `W'ᵀ (C_in, C_out)` contiguous and `b' (C_out)`.
    fn folded(&self) -> Result<(Tensor, Tensor)> {
        let w = self.linear.weight().detach();
        let out = w.dim(0)?;
        let b = match self.linear.bias() {
            Some(b) => b.detach(),
            None => Tensor::zeros(out, w.dtype(), w.device())?,
        };
        let inv_std = self
            .norm
            .running_var()
            .detach()
            .affine(1.0, self.norm.eps())?
            .sqrt()?
            .recip()?;
        let (gamma, beta) = match self.norm.weight_and_bias() {
            Some((g, bt)) => (g.detach(), bt.detach()),
            None => (
                Tensor::ones(out, w.dtype(), w.device())?,
                Tensor::zeros(out, w.dtype(), w.device())?,
            ),
        };
        let scale = gamma.mul(&inv_std)?;
        let w_folded = w.broadcast_mul(&scale.unsqueeze(1)?)?.t()?.contiguous()?;
        let b_folded = b
            .sub(&self.norm.running_mean().detach())?
            .mul(&scale)?
            .add(&beta)?;
        Ok((w_folded, b_folded))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::Device;

    #[test]
    fn folded_evaluation_equals_linear_then_batch_norm() {
        let dev = Device::Cpu;
        let map = candle_nn::VarMap::new();
        let vb = VarBuilder::from_varmap(&map, candle_core::DType::F32, &dev);
        let layer = PointMlp::new(vb, 5, 7).unwrap();
        let x = Tensor::rand(-1.0f32, 1.0, (40, 5), &dev).unwrap();
        layer.forward_t(&x, true).unwrap(); // move the running statistics off (0, 1)
        let folded: Vec<Vec<f32>> = layer.forward_t(&x, false).unwrap().to_vec2().unwrap();
        let plain: Vec<Vec<f32>> = layer
            .norm
            .forward_t(&layer.linear.forward(&x).unwrap(), false)
            .unwrap()
            .relu()
            .unwrap()
            .to_vec2()
            .unwrap();
        for (a, b) in folded.iter().flatten().zip(plain.iter().flatten()) {
            assert!((a - b).abs() < 1e-5, "{a} vs {b}");
        }
    }

    #[test]
    fn hand_set_weights_give_known_values_in_both_modes() {
        let dev = Device::Cpu;
        // y = relu(bn(2x - 1)); eval: running mean 1, var 4 → (y - 1) / 2
        let linear = Linear::new(
            Tensor::new(&[[2.0f32]], &dev).unwrap(),
            Some(Tensor::new(&[-1.0f32], &dev).unwrap()),
        );
        let norm = BatchNorm::new(
            1,
            Tensor::new(&[1.0f32], &dev).unwrap(),
            Tensor::new(&[4.0f32], &dev).unwrap(),
            Tensor::new(&[1.0f32], &dev).unwrap(),
            Tensor::new(&[0.0f32], &dev).unwrap(),
            0.0,
        )
        .unwrap();
        let layer = PointMlp::from_parts(linear, norm);
        let x = Tensor::new(&[[0.0f32], [1.0], [3.0]], &dev).unwrap();
        let eval: Vec<Vec<f32>> = layer.forward_t(&x, false).unwrap().to_vec2().unwrap();
        // 2x - 1 = -1, 1, 5 → (·-1)/2 = -1, 0, 2 → relu
        assert_eq!(eval, vec![vec![0.0], vec![0.0], vec![2.0]]);
        // train: batch mean of (-1, 1, 5) = 5/3, biased variance = 56/9
        let train: Vec<Vec<f32>> = layer.forward_t(&x, true).unwrap().to_vec2().unwrap();
        let (m, s) = (5.0f32 / 3.0, (56.0f32 / 9.0).sqrt());
        let expect = [-1.0f32, 1.0, 5.0].map(|v| ((v - m) / s).max(0.0));
        for (got, want) in train.iter().zip(expect) {
            assert!((got[0] - want).abs() < 1e-4, "{got:?} vs {want}");
        }
    }
}
