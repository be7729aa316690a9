//! TriConv, the graph layer of the face classifier (thesis eq. 6.7, ch. 6.3.3):
//! `f_n' = 1/K Σ_{k∈N(t_n)} MLP([r_{n,k} ‖ f_n − f_k])`, with `r` the relative position
//! encoding of eq. 6.6 ([`FaceGraph`]). The MLP is `Linear(9 + C_in, C_out) → ReLU →
//! Linear(C_out, C_out)`; the thesis does not state its depth. A triangle without links gets
//! zeros.
//!
//! Beyond the printed equation, the messages are averaged, not summed: with K = 20 and three
//! layers the sum grows activations about twentyfold per layer, and an untrained classifier's
//! sigmoid read-out was saturated at exactly 0 or 1 in `f32` on an icosphere (measured),
//! leaving no gradient to learn from.

use candle_core::Tensor;
use candle_nn::{Linear, Module, VarBuilder};

use super::{FaceGraph, column_concat, link_message_mean};
use crate::{Error, Result};

/// Widths of a TriConv layer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TriConvConfig {
    /// Input channels per triangle (1 for the prior of eq. 6.5).
    pub input: usize,
    /// Output channels (128 in the thesis).
    pub output: usize,
}

/// Eq. 6.7 with the MLP `mlp.0` (`(C_out, 9 + C_in)`), `mlp.1` (`(C_out, C_out)`).
#[derive(Clone, Debug)]
pub struct TriConv {
    mlp: [Linear; 2],
}

impl TriConv {
    /// A layer with the widths of `config`, parameters under `vb`.
    pub fn new(vb: VarBuilder, config: &TriConvConfig) -> Result<Self> {
        if config.input == 0 || config.output == 0 {
            return Err(Error::Invalid {
                what: "TriConv widths".into(),
                reason: format!("{config:?}: both must be at least 1"),
            });
        }
        Ok(Self {
            mlp: [
                candle_nn::linear(9 + config.input, config.output, vb.pp("mlp.0"))?,
                candle_nn::linear(config.output, config.output, vb.pp("mlp.1"))?,
            ],
        })
    }

    /// Eq. 6.7: `features: (F, C_in)` over the triangles of `graph` → `(F, C_out)`.
    pub fn forward(&self, features: &Tensor, graph: &FaceGraph) -> Result<Tensor> {
        let (f, _) = features.dims2()?;
        if f != graph.len() {
            return Err(Error::Invalid {
                what: "TriConv features".into(),
                reason: format!("{f} rows for a graph over {} triangles", graph.len()),
            });
        }
        let output = self.mlp[1].weight().dim(0)?;
        let k = graph.width();
        if k == 0 {
            return Ok(Tensor::zeros(
                (f, output),
                features.dtype(),
                features.device(),
            )?);
        }
        // The first layer on a link's `[r_nk ‖ f_n − f_k]` is `W [d_n ‖ f_n] − W [d_k ‖ f_k] + b`
        // (eq. 6.6's `r` is a difference of per-triangle descriptors `d`, [`FaceGraph`]): the
        // weights once per triangle, then a subtraction, the bias and the ReLU per link in one
        // fused pass. The second layer is affine, so it commutes with the mean over the links
        // and runs once per triangle too. Equal to the printed order of operations up to
        // rounding, about `K·(9 + C_in)` times fewer multiplications.
        let first = &self.mlp[0];
        let bias = match first.bias() {
            Some(bias) => bias.clone(),
            None => Tensor::zeros(output, features.dtype(), features.device())?,
        };
        // Scoped so that, outside training, the `(F, C)` projection is freed before the second
        // layer allocates its own.
        let mean = {
            let descriptors = graph.descriptors.to_dtype(features.dtype())?;
            let projected = column_concat(&descriptors, features)?.matmul(&first.weight().t()?)?;
            link_message_mean(&projected, &bias, &graph.neighbours)?
        };
        Ok(self.mlp[1].forward(&mean)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::{DType, Device};
    use candle_nn::VarMap;
    use meshgnn_losses::losses::gradient_disagreement;

    fn strip() -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
        // Random positions: no two barycentre distances (nearly) tie, so the links survive a
        // shift and its rounding.
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(11);
        let v: Vec<[f32; 3]> = (0..8)
            .map(|_| [rng.random(), rng.random(), rng.random()])
            .collect();
        let t: Vec<[u32; 3]> = (0..6).map(|i| [i, i + 1, i + 2]).collect();
        (v, t)
    }

    #[test]
    fn translation_does_not_change_the_output_and_gradients_match_finite_differences() {
        let map = VarMap::new();
        let vb = VarBuilder::from_varmap(&map, DType::F64, &Device::Cpu);
        let conv = TriConv::new(
            vb,
            &TriConvConfig {
                input: 2,
                output: 4,
            },
        )
        .unwrap();
        let (v, t) = strip();
        let up = vec![[0.0, 0.0, 1.0]; v.len()];
        let graph = FaceGraph::new(&v, &up, &t, &[], 3, &Device::Cpu).unwrap();
        let moved: Vec<[f32; 3]> = v.iter().map(|p| [p[0] + 5.0, p[1] - 2.0, p[2]]).collect();
        let moved = FaceGraph::new(&moved, &up, &t, &[], 3, &Device::Cpu).unwrap();
        let f0: Vec<f64> = (0..12).map(|i| ((i * 7 % 5) as f64 - 2.0) * 0.3).collect();
        let x = Tensor::from_slice(&f0, (6, 2), &Device::Cpu).unwrap();
        let a: Vec<Vec<f64>> = conv.forward(&x, &graph).unwrap().to_vec2().unwrap();
        let b: Vec<Vec<f64>> = conv.forward(&x, &moved).unwrap().to_vec2().unwrap();
        for (p, q) in a.iter().flatten().zip(b.iter().flatten()) {
            assert!((p - q).abs() < 1e-4, "{p} vs {q}");
        }
        let weights = Tensor::arange(1f64, 25.0, &Device::Cpu)
            .unwrap()
            .reshape((6, 4))
            .unwrap();
        let worst = gradient_disagreement(&x, |x| -> Result<Tensor> {
            Ok((conv.forward(x, &graph)? * &weights)?.sum_all()?)
        })
        .unwrap();
        assert!(worst.relative_error <= 1e-5, "{worst:?}");
        assert!(worst.largest_gradient > 1e-3, "{worst:?}");
    }

    #[test]
    fn the_reordered_layer_equals_eq_6_7_in_its_printed_order() {
        let map = VarMap::new();
        let vb = VarBuilder::from_varmap(&map, DType::F64, &Device::Cpu);
        let conv = TriConv::new(
            vb,
            &TriConvConfig {
                input: 3,
                output: 5,
            },
        )
        .unwrap();
        let (v, t) = strip();
        let up = vec![[0.0, 0.0, 1.0]; v.len()];
        let graph = FaceGraph::new(&v, &up, &t, &[], 3, &Device::Cpu).unwrap();
        let f0: Vec<f64> = (0..18).map(|i| ((i * 5 % 7) as f64 - 3.0) * 0.4).collect();
        let x = Tensor::from_slice(&f0, (6, 3), &Device::Cpu).unwrap();
        // MLP([r_nk ‖ f_n − f_k]) per link, then the mean over the links.
        let (f, k) = (graph.len(), graph.width());
        let own = x.unsqueeze(1).unwrap().broadcast_as((f, k, 3)).unwrap();
        let own = own.reshape((f * k, 3)).unwrap();
        let others = x.index_select(&graph.neighbours, 0).unwrap();
        let descriptors = graph.descriptors.to_dtype(DType::F64).unwrap();
        let relative = (descriptors
            .unsqueeze(1)
            .unwrap()
            .broadcast_as((f, k, 9))
            .unwrap()
            .reshape((f * k, 9))
            .unwrap()
            - descriptors.index_select(&graph.neighbours, 0).unwrap())
        .unwrap();
        let input = Tensor::cat(&[&relative, &(own - others).unwrap()], 1).unwrap();
        let hidden = conv.mlp[0].forward(&input).unwrap().relu().unwrap();
        let messages = conv.mlp[1].forward(&hidden).unwrap();
        let printed: Vec<Vec<f64>> = messages
            .reshape((f, k, 5))
            .unwrap()
            .mean(1)
            .unwrap()
            .to_vec2()
            .unwrap();
        let got: Vec<Vec<f64>> = conv.forward(&x, &graph).unwrap().to_vec2().unwrap();
        for (p, q) in printed.iter().flatten().zip(got.iter().flatten()) {
            assert!((p - q).abs() < 1e-12, "{p} vs {q}");
        }
    }

    #[test]
    fn a_lone_triangle_gets_zeros() {
        let map = VarMap::new();
        let vb = VarBuilder::from_varmap(&map, DType::F32, &Device::Cpu);
        let conv = TriConv::new(
            vb,
            &TriConvConfig {
                input: 1,
                output: 3,
            },
        )
        .unwrap();
        let (v, _) = strip();
        let up = vec![[0.0, 0.0, 1.0]; v.len()];
        let graph = FaceGraph::new(&v, &up, &[[0, 1, 2]], &[], 20, &Device::Cpu).unwrap();
        let x = Tensor::ones((1, 1), DType::F32, &Device::Cpu).unwrap();
        let y: Vec<Vec<f32>> = conv.forward(&x, &graph).unwrap().to_vec2().unwrap();
        assert_eq!(y, vec![vec![0.0; 3]]);
    }
}
