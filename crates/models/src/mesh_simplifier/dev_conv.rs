//! DevConv, the graph layer of the neural mesh simplifier (thesis eq. 6.1, ch. 6.3.1):
//! `f_i = σ(W_φ max_{j∈N(i)} W_θ(x_i − x_j))`, the maximum taken per channel. It encodes how far
//! a point deviates from its neighbourhood: sharp and rough regions get larger values than
//! smooth ones, and the maximum of relative features singles out outliers (the thesis'
//! argument for its robustness to noise). σ is ReLU (ch. 6.4).
//!
//! `W_θ` has no bias: in `W_θ(x_i − x_j) + b` the bias would only shift the maximum by a
//! constant that `W_φ`'s bias already absorbs. Because only differences enter, the layer is
//! invariant to a translation of its input (tested).

use candle_core::Tensor;
use candle_nn::{Linear, Module, VarBuilder};

use super::{NeighbourSlots, linear_relu, neighbour_deviation_maximum};
use crate::{Error, Result};

/// Widths of a DevConv layer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DevConvConfig {
    /// Input channels (3 for coordinates).
    pub input: usize,
    /// Output channels (64 in the thesis).
    pub output: usize,
}

/// Eq. 6.1 with learnable `W_θ` (`theta.weight (C_out, C_in)`, no bias) and `W_φ`
/// (`phi.weight (C_out, C_out)`, `phi.bias`).
#[derive(Clone, Debug)]
pub struct DevConv {
    theta: Linear,
    phi: Linear,
}

impl DevConv {
    /// A layer with the widths of `config`, parameters under `vb`.
    ///
    /// ```
    /// use candle_core::{DType, Device, Tensor};
    /// use candle_nn::{VarBuilder, VarMap};
    /// use meshgnn_models::mesh_simplifier::{DevConv, DevConvConfig, NeighbourSlots};
    /// let map = VarMap::new();
    /// let vb = VarBuilder::from_varmap(&map, DType::F32, &Device::Cpu);
    /// let conv = DevConv::new(vb, &DevConvConfig { input: 3, output: 8 })?;
    /// let slots = NeighbourSlots::from_rows(&[vec![1], vec![0]], &Device::Cpu)?;
    /// let x = Tensor::new(&[[0f32, 0.0, 0.0], [1.0, 0.0, 0.0]], &Device::Cpu)?;
    /// assert_eq!(conv.forward(&x, &slots)?.dims(), &[2, 8]);
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn new(vb: VarBuilder, config: &DevConvConfig) -> Result<Self> {
        if config.input == 0 || config.output == 0 {
            return Err(Error::Invalid {
                what: "DevConv widths".into(),
                reason: format!("{config:?}: both must be at least 1"),
            });
        }
        Ok(Self {
            theta: candle_nn::linear_no_bias(config.input, config.output, vb.pp("theta"))?,
            phi: candle_nn::linear(config.output, config.output, vb.pp("phi"))?,
        })
    }

    /// From raw parts (tests, hand-set weights).
    pub fn from_parts(theta: Linear, phi: Linear) -> Self {
        Self { theta, phi }
    }

    /// Eq. 6.1: `features: (N, C_in)` over the points of `slots` → `(N, C_out)`.
    pub fn forward(&self, features: &Tensor, slots: &NeighbourSlots) -> Result<Tensor> {
        let (n, _) = features.dims2()?;
        if n != slots.len() {
            return Err(Error::Invalid {
                what: "DevConv features".into(),
                reason: format!("{n} rows for a graph over {} points", slots.len()),
            });
        }
        // max_j W_θ(x_i − x_j) = max_j (W_θ x_i − W_θ x_j): project once, then take the
        // maximum over the neighbours in place. Each `(N, C)` intermediate is dropped as soon
        // as the next exists: at inference nothing else holds them, and the fewer live at
        // once, the less fresh memory the kernel must fault in and zero.
        let projected = self.theta.forward(features)?;
        let largest = neighbour_deviation_maximum(&projected, slots.indices())?;
        drop(projected);
        Ok(linear_relu(largest, &self.phi)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::{DType, Device};
    use candle_nn::VarMap;
    use meshgnn_losses::losses::gradient_disagreement;

    fn identity_layer(bias: f32) -> DevConv {
        let eye = Tensor::eye(3, DType::F32, &Device::Cpu).unwrap();
        let b = Tensor::full(bias, 3, &Device::Cpu).unwrap();
        DevConv::from_parts(Linear::new(eye.clone(), None), Linear::new(eye, Some(b)))
    }

    #[test]
    fn identity_weights_give_the_largest_coordinate_deviation() {
        // f_i = ReLU(max_j (x_i − x_j)) per coordinate.
        let x = [[0f32, 0.0, 0.0], [1.0, -2.0, 0.5], [-1.0, 3.0, 0.0]];
        let rows = [vec![1, 2], vec![0], vec![0, 1]];
        let slots = NeighbourSlots::from_rows(&rows, &Device::Cpu).unwrap();
        let input = Tensor::new(&x, &Device::Cpu).unwrap();
        let got: Vec<Vec<f32>> = identity_layer(0.0)
            .forward(&input, &slots)
            .unwrap()
            .to_vec2()
            .unwrap();
        let expected = |i: usize| -> Vec<f32> {
            (0..3)
                .map(|c| {
                    rows[i]
                        .iter()
                        .map(|&j| x[i][c] - x[j as usize][c])
                        .fold(f32::NEG_INFINITY, f32::max)
                        .max(0.0)
                })
                .collect()
        };
        for (i, row) in got.iter().enumerate() {
            assert_eq!(row, &expected(i), "point {i}");
        }
        // Point 1 has one neighbour, padded by repetition: its maximum is that neighbour's.
        assert_eq!(got[1], vec![1.0, 0.0, 0.5]);
    }

    #[test]
    fn isolated_points_see_zero_deviation_and_the_bias() {
        let slots = NeighbourSlots::from_rows(&[vec![], vec![]], &Device::Cpu).unwrap();
        let x = Tensor::new(&[[5f32, 1.0, 2.0], [0.0, 0.0, 9.0]], &Device::Cpu).unwrap();
        let got: Vec<Vec<f32>> = identity_layer(0.25)
            .forward(&x, &slots)
            .unwrap()
            .to_vec2()
            .unwrap();
        assert_eq!(got, vec![vec![0.25; 3], vec![0.25; 3]]);
    }

    #[test]
    fn translation_and_neighbour_order_do_not_change_the_output() {
        let map = VarMap::new();
        let vb = VarBuilder::from_varmap(&map, DType::F32, &Device::Cpu);
        let conv = DevConv::new(
            vb,
            &DevConvConfig {
                input: 3,
                output: 16,
            },
        )
        .unwrap();
        let mesh = meshgnn_geometry::icosphere(2);
        let adjacency = meshgnn_graph::vertex_adjacency(&mesh).unwrap();
        let slots = NeighbourSlots::from_adjacency(&adjacency, &Device::Cpu).unwrap();
        let reversed: Vec<Vec<u32>> = (0..adjacency.rows())
            .map(|i| adjacency.row(i).0.iter().rev().copied().collect())
            .collect();
        let reversed = NeighbourSlots::from_rows(&reversed, &Device::Cpu).unwrap();
        let v = mesh.vertices();
        let x = Tensor::from_slice(v.as_flattened(), (v.len(), 3), &Device::Cpu).unwrap();
        let shifted = x.broadcast_add(&Tensor::new(&[3f32, -1.0, 0.5], &Device::Cpu).unwrap());
        let base: Vec<Vec<f32>> = conv.forward(&x, &slots).unwrap().to_vec2().unwrap();
        for (input, graph) in [(&shifted.unwrap(), &slots), (&x, &reversed)] {
            let other: Vec<Vec<f32>> = conv.forward(input, graph).unwrap().to_vec2().unwrap();
            for (a, b) in base.iter().flatten().zip(other.iter().flatten()) {
                assert!((a - b).abs() <= 1e-5 * (1.0 + a.abs()), "{a} vs {b}");
            }
        }
    }

    #[test]
    fn gradient_matches_finite_differences() {
        let map = VarMap::new();
        let vb = VarBuilder::from_varmap(&map, DType::F64, &Device::Cpu);
        let conv = DevConv::new(
            vb,
            &DevConvConfig {
                input: 3,
                output: 5,
            },
        )
        .unwrap();
        let rows = [vec![1, 2, 3], vec![0, 2], vec![3], vec![0, 1, 2]];
        let slots = NeighbourSlots::from_rows(&rows, &Device::Cpu).unwrap();
        let x = Tensor::new(
            &[
                [0.1f64, -0.3, 0.7],
                [0.9, 0.2, -0.4],
                [-0.6, 0.5, 0.3],
                [0.25, -0.8, 0.45],
            ],
            &Device::Cpu,
        )
        .unwrap();
        // A weighted sum, so that every output channel's gradient matters differently.
        let weights = Tensor::arange(1f64, 21.0, &Device::Cpu)
            .unwrap()
            .reshape((4, 5))
            .unwrap();
        let worst = gradient_disagreement(&x, |x| -> Result<Tensor> {
            Ok((conv.forward(x, &slots)? * &weights)?.sum_all()?)
        })
        .unwrap();
        assert!(worst.relative_error <= 1e-5, "{worst:?}");
        assert!(worst.largest_gradient > 1e-3, "{worst:?}");
    }
}
