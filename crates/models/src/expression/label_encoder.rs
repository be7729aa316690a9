//! The temporal encoder `E` of the expression generator (thesis eq. 4.1, Fig. 4.1): an LSTM
//! that reads the per-frame expression label signal `e_t ∈ R^6` (one-hot expression × motion
//! amplitude, eq. 4.3) and outputs the expression latent `z_t = h_t` of every frame.
//!
//! # Conventions
//! - Labels are `(B, T, 6)`, latents `(B, T, H)`; the state starts at zero for every sequence.
//! - Parameters in PyTorch's `nn.LSTM` layout and names (`weight_ih_l0 (4H, 6)`,
//!   `weight_hh_l0 (4H, H)`, `bias_ih_l0`, `bias_hh_l0`; gates in the order input, forget,
//!   cell, output), so weights trained with PyTorch load unchanged.

use candle_core::Tensor;
use candle_nn::VarBuilder;
use candle_nn::rnn::{LSTM, LSTMConfig, RNN};

use crate::{Error, Result};

/// Width of the label signal: one channel per expression.
pub const LABEL_CHANNELS: usize = 6;

/// `(B, T, 6)` label signals → `(B, T, H)` latents.
#[derive(Debug, Clone)]
pub struct LabelEncoder {
    lstm: LSTM,
    hidden_size: usize,
}

impl LabelEncoder {
    /// An LSTM of `hidden_size` units (64 in the thesis) with parameters from `vb`.
    pub fn new(vb: VarBuilder, hidden_size: usize) -> Result<Self> {
        if hidden_size == 0 {
            return Err(Error::Invalid {
                what: "label encoder".into(),
                reason: "hidden size must be positive".into(),
            });
        }
        Ok(Self {
            lstm: candle_nn::lstm(LABEL_CHANNELS, hidden_size, LSTMConfig::default(), vb)?,
            hidden_size,
        })
    }

    /// Latent size `H`.
    pub fn hidden_size(&self) -> usize {
        self.hidden_size
    }

    /// `labels: (B, T, 6)` → `z: (B, T, H)`, `z_t = h_t` of the LSTM run from a zero state.
    pub fn forward(&self, labels: &Tensor) -> Result<Tensor> {
        match labels.dims() {
            [_, t, c] if *c == LABEL_CHANNELS && *t > 0 => {}
            dims => {
                return Err(Error::Invalid {
                    what: "expression labels".into(),
                    reason: format!("shape {dims:?}, expected (B, T, {LABEL_CHANNELS}), T ≥ 1"),
                });
            }
        }
        let states = self.lstm.seq(labels)?;
        Ok(self.lstm.states_to_tensor(&states)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::{DType, Device};
    use candle_nn::VarMap;

    fn sigmoid(x: f64) -> f64 {
        1.0 / (1.0 + (-x).exp())
    }

    #[test]
    fn one_unit_lstm_matches_a_hand_computed_step() {
        // H = 1: every gate row is one weight row; only channel 0 of the input is weighted.
        let vars = VarMap::new();
        let vb = VarBuilder::from_varmap(&vars, DType::F32, &Device::Cpu);
        let encoder = LabelEncoder::new(vb, 1).unwrap();
        let w_ih = [0.5f32, -0.25, 1.0, 0.75];
        let w_hh = [0.1f32, 0.2, -0.3, 0.4];
        let b = [0.05f32, -0.1, 0.2, 0.0];
        {
            let data = vars.data().lock().unwrap();
            let set = |name: &str, values: Vec<f32>, dims: &[usize]| {
                data[name]
                    .set(&Tensor::from_vec(values, dims, &Device::Cpu).unwrap())
                    .unwrap();
            };
            let mut ih = vec![0.0f32; 4 * 6];
            for g in 0..4 {
                ih[g * 6] = w_ih[g];
            }
            set("weight_ih_l0", ih, &[4, 6]);
            set("weight_hh_l0", w_hh.to_vec(), &[4, 1]);
            set("bias_ih_l0", b.to_vec(), &[4]);
            set("bias_hh_l0", vec![0.0; 4], &[4]);
        }
        // Two frames: x = 0.8 then x = 0.2 on channel 0.
        let mut labels = vec![0.0f32; 12];
        labels[0] = 0.8;
        labels[6] = 0.2;
        let labels = Tensor::from_vec(labels, (1, 2, 6), &Device::Cpu).unwrap();
        let z = encoder.forward(&labels).unwrap();
        assert_eq!(z.dims(), &[1, 2, 1]);
        let z: Vec<f32> = z.flatten_all().unwrap().to_vec1().unwrap();
        let (mut h, mut c) = (0.0f64, 0.0f64);
        for (t, x) in [0.8f64, 0.2].into_iter().enumerate() {
            let pre = |g: usize| f64::from(w_ih[g]) * x + f64::from(w_hh[g]) * h + f64::from(b[g]);
            let (i, f, g, o) = (
                sigmoid(pre(0)),
                sigmoid(pre(1)),
                pre(2).tanh(),
                sigmoid(pre(3)),
            );
            c = f * c + i * g;
            h = o * c.tanh();
            assert!(
                (f64::from(z[t]) - h).abs() < 1e-6,
                "frame {t}: {} vs {h}",
                z[t]
            );
        }
        // Frame 0 by hand: i = σ(0.45), f = σ(−0.3), g = tanh(1.0), o = σ(0.6).
        let c0 = sigmoid(0.45) * 1.0f64.tanh();
        assert!((f64::from(z[0]) - sigmoid(0.6) * c0.tanh()).abs() < 1e-6);
        assert!(encoder.forward(&labels.narrow(2, 0, 5).unwrap()).is_err());
    }
}
