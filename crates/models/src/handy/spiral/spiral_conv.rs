//! Spiral convolution (thesis eq. 2.28-2.29; Bouritsas et al., "Neural 3D Morphable Models:
//! Spiral Convolutional Networks for 3D Shape Representation Learning and Generation", ICCV
//! 2019; Gong et al., "SpiralNet++", ICCV-W 2019): every vertex concatenates the features of
//! its spiral `S(v, k)` (fixed length `L`) and applies one shared linear map
//! `v'ᵢ = W · ‖_{j ∈ S(vᵢ)} vⱼ + b` (`γ_Θ` of eq. 2.29 a linear layer, `h_Θ` the identity; the
//! non-linearity follows the layer, as the thesis recommends).
//!
//! # Conventions
//! - Features are `(B, V, C)` (batch, vertex, channel); spirals are a flat `u32` index tensor
//!   `(V·L)`, row `v` being the spiral of vertex `v` (see [`crate::handy::spiral::TemplateTensors`]).
//! - The weight is `(C_out, L·C_in)` and multiplies the spiral entries in order, channels
//!   fastest: column `l·C_in + c` is channel `c` of spiral entry `l`.
//! - Padding ([`SpiralPadding`]): `meshgnn_graph::Spirals` pads a short spiral by repeating its
//!   last real entry. With [`SpiralPadding::Repeat`] those indices are used as they are (the
//!   padded slots see the last real neighbour again); with [`SpiralPadding::Zero`] they are
//!   replaced by the index `V` of an appended all-zero row, so a padded slot contributes 0
//!   (Neural3DMM's dummy vertex).

use candle_core::{DType, Tensor};
use candle_nn::{Linear, VarBuilder};
use serde::{Deserialize, Serialize};

use crate::{Error, Result};

/// How the padded entries of a short spiral contribute (module docs, `# Conventions`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum SpiralPadding {
    /// Padded slots gather the last real entry again (`meshgnn_graph::Spirals` as computed).
    #[default]
    Repeat,
    /// Padded slots gather an all-zero feature row (index `V`).
    Zero,
}

/// Hyper-parameters of one [`SpiralConv`]; update with `..Default::default()`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct SpiralConvConfig {
    /// Spiral length `L` (entries per vertex, the vertex itself first). Default 9
    /// (Neural3DMM / SpiralNet++).
    pub length: usize,
    /// Treatment of padded entries. Default [`SpiralPadding::Repeat`].
    pub padding: SpiralPadding,
}

impl Default for SpiralConvConfig {
    fn default() -> Self {
        Self {
            length: 9,
            padding: SpiralPadding::Repeat,
        }
    }
}

/// Eq. 2.29 with a linear `γ_Θ`: `(B, V, C_in)` features → `(B, V, C_out)`.
#[derive(Debug, Clone)]
pub struct SpiralConv {
    linear: Linear,
    in_channels: usize,
    out_channels: usize,
    config: SpiralConvConfig,
}

impl SpiralConv {
    /// A layer whose weight `(C_out, L·C_in)` and bias `(C_out)` come from `vb` under the
    /// names `weight` and `bias` (PyTorch's default uniform `±1/√(L·C_in)` init when missing).
    pub fn new(
        vb: VarBuilder,
        in_channels: usize,
        out_channels: usize,
        config: SpiralConvConfig,
    ) -> Result<Self> {
        check_config(in_channels, out_channels, &config)?;
        let linear = candle_nn::linear(in_channels * config.length, out_channels, vb)?;
        Ok(Self {
            linear,
            in_channels,
            out_channels,
            config,
        })
    }

    /// A layer from raw tensors: `weight: (C_out, L·C_in)`, `bias: (C_out)`.
    ///
    /// ```
    /// use candle_core::{Device, Tensor};
    /// use meshgnn_models::spiral::{SpiralConv, SpiralConvConfig};
    /// // L = 2, C_in = 1, C_out = 1: y_v = x_v + 10·x_{next(v)}.
    /// let cfg = SpiralConvConfig { length: 2, ..Default::default() };
    /// let conv = SpiralConv::from_tensors(
    ///     Tensor::new(&[[1.0f32, 10.0]], &Device::Cpu)?,
    ///     Tensor::new(&[0.0f32], &Device::Cpu)?,
    ///     cfg,
    /// )?;
    /// let x = Tensor::new(&[[[1.0f32], [2.0], [3.0]]], &Device::Cpu)?; // (1, 3, 1)
    /// let spirals = Tensor::new(&[0u32, 1, 1, 2, 2, 0], &Device::Cpu)?; // (3·2)
    /// let y = conv.forward(&x, &spirals)?;
    /// assert_eq!(y.flatten_all()?.to_vec1::<f32>()?, vec![21.0, 32.0, 13.0]);
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn from_tensors(weight: Tensor, bias: Tensor, config: SpiralConvConfig) -> Result<Self> {
        let (out_channels, columns) = weight.dims2()?;
        if config.length == 0 || columns % config.length != 0 {
            return Err(Error::Invalid {
                what: "spiral convolution weight".into(),
                reason: format!(
                    "has {columns} columns, not a positive multiple of the spiral length {}",
                    config.length
                ),
            });
        }
        if bias.dims() != [out_channels] {
            return Err(Error::Invalid {
                what: "spiral convolution bias".into(),
                reason: format!("shape {:?}, expected [{out_channels}]", bias.dims()),
            });
        }
        let in_channels = columns / config.length;
        check_config(in_channels, out_channels, &config)?;
        Ok(Self {
            linear: Linear::new(weight, Some(bias)),
            in_channels,
            out_channels,
            config,
        })
    }

    /// Input channels `C_in`.
    pub fn in_channels(&self) -> usize {
        self.in_channels
    }

    /// Output channels `C_out`.
    pub fn out_channels(&self) -> usize {
        self.out_channels
    }

    /// The layer's hyper-parameters.
    pub fn config(&self) -> SpiralConvConfig {
        self.config
    }

    /// Eq. 2.29: `x: (B, V, C_in)`, `spirals: (V·L)` `u32` (entries `< V`, or `≤ V` with
    /// [`SpiralPadding::Zero`]) → `(B, V, C_out)`. One `index_select` over the vertex axis and
    /// one matrix product `(B·V, L·C_in) × (L·C_in, C_out)`: no per-vertex loop.
    pub fn forward(&self, x: &Tensor, spirals: &Tensor) -> Result<Tensor> {
        let (batch, vertices, channels) = x.dims3().map_err(|_| Error::Invalid {
            what: "spiral convolution input".into(),
            reason: format!("shape {:?}, expected (B, V, C)", x.dims()),
        })?;
        if channels != self.in_channels {
            return Err(Error::Invalid {
                what: "spiral convolution input".into(),
                reason: format!(
                    "has {channels} channels, the layer takes {}",
                    self.in_channels
                ),
            });
        }
        let length = self.config.length;
        if spirals.dims() != [vertices * length] || spirals.dtype() != DType::U32 {
            return Err(Error::Invalid {
                what: "spirals".into(),
                reason: format!(
                    "{:?} {:?}, expected a u32 tensor of V·L = {vertices}·{length} entries",
                    spirals.dtype(),
                    spirals.dims()
                ),
            });
        }
        let source = match self.config.padding {
            SpiralPadding::Repeat => x.contiguous()?,
            SpiralPadding::Zero => {
                let zeros = Tensor::zeros((batch, 1, channels), x.dtype(), x.device())?;
                Tensor::cat(&[x, &zeros], 1)?
            }
        };
        let gathered = source.index_select(spirals, 1)?; // (B, V·L, C_in)
        let rows = gathered.reshape((batch * vertices, length * channels))?;
        let out = rows.matmul(&self.linear.weight().t()?)?;
        let out = match self.linear.bias() {
            Some(bias) => out.broadcast_add(bias)?,
            None => out,
        };
        Ok(out.reshape((batch, vertices, self.out_channels))?)
    }

    /// The weight `(C_out, L·C_in)`.
    pub fn weight(&self) -> &Tensor {
        self.linear.weight()
    }
}

fn check_config(in_channels: usize, out_channels: usize, config: &SpiralConvConfig) -> Result<()> {
    if in_channels == 0 || out_channels == 0 || config.length == 0 {
        return Err(Error::Invalid {
            what: "spiral convolution".into(),
            reason: format!(
                "channels {in_channels} → {out_channels} with spiral length {}: all must be \
                 positive",
                config.length
            ),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::Device;
    use meshgnn_geometry::grid_plane;
    use meshgnn_graph::spiral_sequences;
    use meshgnn_losses::losses::gradient_disagreement;

    fn conv(weights: &[f64], bias: f64, length: usize, padding: SpiralPadding) -> SpiralConv {
        let w = Tensor::from_slice(weights, (1, weights.len()), &Device::Cpu).unwrap();
        let b = Tensor::new(&[bias], &Device::Cpu).unwrap();
        SpiralConv::from_tensors(w, b, SpiralConvConfig { length, padding }).unwrap()
    }

    #[test]
    fn grid_known_answer() {
        // grid_plane(2, 2): vertex j·3 + i. Hand-derived spirals of length 3 (module rule):
        // vertex 4 → [4, 0, 1], corner 0 → [0, 1, 4], corner 8 → [8, 7, 4].
        let spirals = spiral_sequences(&grid_plane(2, 2), 3, 1).unwrap();
        assert_eq!(spirals.row(4), &[4, 0, 1]);
        assert_eq!(spirals.row(0), &[0, 1, 4]);
        assert_eq!(spirals.row(8), &[8, 7, 4]);
        let layer = conv(&[1.0, 10.0, 100.0], 0.5, 3, SpiralPadding::Repeat);
        let x: Vec<f64> = (1..=9).map(f64::from).collect();
        let xt = Tensor::from_slice(&x, (1, 9, 1), &Device::Cpu).unwrap();
        let idx = Tensor::from_slice(&spirals.indices, 27, &Device::Cpu).unwrap();
        let y: Vec<f64> = layer
            .forward(&xt, &idx)
            .unwrap()
            .flatten_all()
            .unwrap()
            .to_vec1()
            .unwrap();
        // x_v = v + 1: y_4 = 5 + 10·1 + 100·2 + 0.5, y_0 = 1 + 20 + 500 + 0.5, y_8 = 9 + 80 + 500 + 0.5.
        assert_eq!((y[4], y[0], y[8]), (215.5, 521.5, 589.5));
        for (v, &yv) in y.iter().enumerate() {
            let row = spirals.row(v);
            let expected =
                x[row[0] as usize] + 10.0 * x[row[1] as usize] + 100.0 * x[row[2] as usize] + 0.5;
            assert_eq!(yv, expected, "vertex {v}");
        }
    }

    #[test]
    fn channels_and_batches_are_laid_out_as_documented() {
        // C_in = 2, L = 2, C_out = 2; column l·C_in + c is channel c of entry l.
        let w = Tensor::new(
            &[[1.0f32, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]],
            &Device::Cpu,
        )
        .unwrap();
        let b = Tensor::zeros(2, DType::F32, &Device::Cpu).unwrap();
        let layer = SpiralConv::from_tensors(
            w,
            b,
            SpiralConvConfig {
                length: 2,
                ..Default::default()
            },
        )
        .unwrap();
        let x = Tensor::new(
            &[[[1.0f32, 2.0], [3.0, 4.0]], [[5.0, 6.0], [7.0, 8.0]]],
            &Device::Cpu,
        )
        .unwrap();
        let idx = Tensor::new(&[0u32, 1, 1, 0], &Device::Cpu).unwrap();
        let y = layer.forward(&x, &idx).unwrap().to_vec3::<f32>().unwrap();
        // Output 0 = channel 0 of the vertex itself, output 1 = channel 1 of its neighbour.
        assert_eq!(
            y,
            vec![
                vec![vec![1.0, 4.0], vec![3.0, 2.0]],
                vec![vec![5.0, 8.0], vec![7.0, 6.0]]
            ]
        );
        assert!(
            layer
                .forward(&x, &Tensor::new(&[0u32, 1, 1], &Device::Cpu).unwrap())
                .is_err()
        );
        assert!(layer.forward(&x.narrow(2, 0, 1).unwrap(), &idx).is_err());
    }

    #[test]
    fn padding_repeats_or_zeroes() {
        // Length 10 on a 9-vertex grid: one padded slot per spiral.
        let spirals = spiral_sequences(&grid_plane(2, 2), 10, 1).unwrap();
        assert!(spirals.valid.iter().all(|&n| n == 9));
        let mut weights = vec![0.0; 10];
        weights[9] = 1.0;
        let x: Vec<f64> = (1..=9).map(f64::from).collect();
        let xt = Tensor::from_slice(&x, (1, 9, 1), &Device::Cpu).unwrap();
        let repeat_idx = Tensor::from_slice(&spirals.indices, 90, &Device::Cpu).unwrap();
        let repeat = conv(&weights, 0.0, 10, SpiralPadding::Repeat);
        let y: Vec<f64> = repeat
            .forward(&xt, &repeat_idx)
            .unwrap()
            .flatten_all()
            .unwrap()
            .to_vec1()
            .unwrap();
        for (v, &yv) in y.iter().enumerate() {
            assert_eq!(
                yv,
                x[spirals.row(v)[8] as usize],
                "repeats the last real entry"
            );
        }
        let zero_idx: Vec<u32> = spirals
            .indices
            .chunks(10)
            .flat_map(|r| r[..9].iter().copied().chain([9]))
            .collect();
        let zero_idx = Tensor::from_vec(zero_idx, 90, &Device::Cpu).unwrap();
        let zero = conv(&weights, 0.0, 10, SpiralPadding::Zero);
        let y: Vec<f64> = zero
            .forward(&xt, &zero_idx)
            .unwrap()
            .flatten_all()
            .unwrap()
            .to_vec1()
            .unwrap();
        assert!(y.iter().all(|&v| v == 0.0));
    }

    #[test]
    fn finite_difference_gradients() {
        let spirals = spiral_sequences(&grid_plane(2, 2), 4, 1).unwrap();
        let idx = Tensor::from_slice(&spirals.indices, 36, &Device::Cpu).unwrap();
        let w0: Vec<f64> = (0..24)
            .map(|k| ((k * 7 % 11) as f64 - 5.0) / 10.0)
            .collect();
        let x0: Vec<f64> = (0..36).map(|k| ((k * 5 % 13) as f64 - 6.0) / 7.0).collect();
        let bias = Tensor::new(&[0.1f64, -0.2, 0.3], &Device::Cpu).unwrap();
        let loss = |w: &Tensor, x: &Tensor| -> Result<Tensor> {
            let layer = SpiralConv::from_tensors(
                w.clone(),
                bias.clone(),
                SpiralConvConfig {
                    length: 4,
                    ..Default::default()
                },
            )?;
            // A smooth, non-linear scalar of the output.
            Ok(layer.forward(x, &idx)?.tanh()?.sqr()?.sum_all()?)
        };
        let w = Tensor::from_vec(w0, (3, 8), &Device::Cpu).unwrap();
        let x = Tensor::from_vec(x0, (2, 9, 2), &Device::Cpu).unwrap();
        for worst in [
            gradient_disagreement(&w, |w| loss(w, &x)).unwrap(),
            gradient_disagreement(&x, |x| loss(&w, x)).unwrap(),
        ] {
            assert!(worst.relative_error < 1e-6, "{worst:?}");
            assert!(worst.largest_gradient > 1e-3, "{worst:?}");
        }
    }
}
