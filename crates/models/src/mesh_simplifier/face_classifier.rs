//! The face classifier of the neural mesh simplifier (thesis ch. 6.3.3 and 6.4): three TriConv
//! layers (eq. 6.7, 128 channels, ReLU) on the k = 20 barycentre graph of the candidate
//! triangles, fed the eq. 6.5 prior, give every candidate its inclusion probability `p_t`.
//!
//! The thesis tops the last layer with a "softmax to constrain the triangle probabilities to
//! the (0, 1) interval" and keeps the faces with `p_t > 0.5`: a softmax over all candidates
//! could not put two faces above 0.5, so this is read as the two-class softmax of each
//! triangle, i.e. a sigmoid of a linear read-out (`score`).

use candle_core::Tensor;
use candle_nn::{Linear, Module, VarBuilder};

use super::candidate_features::CANDIDATE_FEATURES;
use super::{FaceGraph, TriConv, TriConvConfig};
use crate::{Error, Result};

/// Hyper-parameters; defaults are the thesis' (ch. 6.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FaceClassifierConfig {
    /// Channels of every TriConv layer (128).
    pub hidden: usize,
    /// Number of TriConv layers (3).
    pub layers: usize,
    /// k of the barycentre graph (20).
    pub neighbours: usize,
}

impl Default for FaceClassifierConfig {
    fn default() -> Self {
        Self {
            hidden: 128,
            layers: 3,
            neighbours: 20,
        }
    }
}

/// TriConv layers `layers.{l}` and the read-out `score`.
#[derive(Clone, Debug)]
pub struct FaceClassifier {
    layers: Vec<TriConv>,
    score: Linear,
}

impl FaceClassifier {
    /// The classifier of `config`, parameters under `vb`.
    ///
    /// ```
    /// use candle_core::{DType, Device, Tensor};
    /// use candle_nn::{VarBuilder, VarMap};
    /// use meshgnn_models::mesh_simplifier::{FaceClassifier, FaceClassifierConfig, FaceGraph};
    /// let map = VarMap::new();
    /// let vb = VarBuilder::from_varmap(&map, DType::F32, &Device::Cpu);
    /// let classifier = FaceClassifier::new(vb, &FaceClassifierConfig::default())?;
    /// let mesh = meshgnn_geometry::icosphere(1);
    /// let (v, t) = (mesh.vertices(), mesh.triangles());
    /// let graph = FaceGraph::new(v, v, t, &[], 20, &Device::Cpu)?;
    /// let prior = Tensor::full(0.5f32, 80, &Device::Cpu)?;
    /// assert_eq!(classifier.forward(&prior, &graph)?.dims(), &[80]);
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn new(vb: VarBuilder, config: &FaceClassifierConfig) -> Result<Self> {
        if config.layers == 0 {
            return Err(Error::Invalid {
                what: "face classifier config".into(),
                reason: "needs at least one TriConv layer".into(),
            });
        }
        let layers = (0..config.layers)
            .map(|l| {
                let widths = TriConvConfig {
                    input: if l == 0 {
                        1 + CANDIDATE_FEATURES
                    } else {
                        config.hidden
                    },
                    output: config.hidden,
                };
                TriConv::new(vb.pp(format!("layers.{l}")), &widths)
            })
            .collect::<Result<Vec<_>>>()?;
        let score = candle_nn::linear(config.hidden, 1, vb.pp("score"))?;
        Ok(Self { layers, score })
    }

    /// `p_t` of every candidate: `prior: (F)` (eq. 6.5) over the triangles of `graph` → `(F)`
    /// in (0, 1).
    pub fn forward(&self, prior: &Tensor, graph: &FaceGraph) -> Result<Tensor> {
        let mut features = Tensor::cat(&[&prior.unsqueeze(1)?, &graph.features], 1)?;
        for layer in &self.layers {
            features = layer.forward(&features, graph)?.relu()?;
        }
        Ok(candle_nn::ops::sigmoid(&self.score.forward(&features)?)?.squeeze(1)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::{DType, Device};
    use candle_nn::VarMap;

    #[test]
    fn untrained_probabilities_are_not_saturated_and_carry_gradients_to_every_layer() {
        let map = VarMap::new();
        let vb = VarBuilder::from_varmap(&map, DType::F32, &Device::Cpu);
        let config = FaceClassifierConfig {
            hidden: 16,
            ..Default::default()
        };
        let classifier = FaceClassifier::new(vb, &config).unwrap();
        let mesh = meshgnn_geometry::icosphere(2);
        // The unit sphere's positions are its normals.
        let graph = FaceGraph::new(
            mesh.vertices(),
            mesh.vertices(),
            mesh.triangles(),
            &mesh.triangles()[..160],
            20,
            &Device::Cpu,
        )
        .unwrap();
        let prior: Vec<f32> = (0..320).map(|i| (i % 7) as f32 / 7.0).collect();
        let prior = Tensor::from_vec(prior, 320, &Device::Cpu).unwrap();
        let p = classifier.forward(&prior, &graph).unwrap();
        let values: Vec<f32> = p.to_vec1().unwrap();
        // Untrained and not saturated (a summed TriConv read exactly 0 or 1 here).
        assert!(values.iter().all(|&v| v > 0.05 && v < 0.95), "{values:?}");
        let grads = p.sum_all().unwrap().backward().unwrap();
        let data = map.data().lock().unwrap();
        for name in [
            "layers.0.mlp.0.weight",
            "layers.2.mlp.1.weight",
            "score.weight",
        ] {
            let g = grads.get(data[name].as_tensor()).unwrap();
            let norm: f32 = g.sqr().unwrap().sum_all().unwrap().to_scalar().unwrap();
            assert!(norm > 0.0, "{name}");
        }
    }
}
