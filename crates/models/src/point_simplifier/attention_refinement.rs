//! AttRef, the attention-based refinement layer of thesis eq. 5.5 (ch. 5.3.2): each selected
//! cluster centre moves by
//! `Δ_i = s_i · tanh(γ( Σ_{j∈N_i} α_ij φ([f_j ‖ (p_j − p_{c_i}) / s_i]) ))`,
//! `α_ij = softmax_j( θ_q(f_j)ᵀ θ_k(f_i) / √d )` (scaled dot-product attention, Vaswani et al.
//! 2017, "Attention is all you need", NeurIPS), over its k = 15 nearest input points.
//!
//! # Conventions
//! - `φ`: `Linear(C + 3, h) → ReLU → Linear(h, 3)` ("filter size 3", ch. 5.6).
//! - `γ`: `Linear(3, g) → ReLU → Linear(g, 3)` without biases, so `γ(0) = 0`: a centre whose
//!   messages vanish stays on the input surface.
//! - `s_i` is the neighbourhood radius of [`super::RefinementGraph`] (beyond the thesis:
//!   density invariance). The `1/|N_i|` of eq. 5.5 is dropped: the softmax weights already sum
//!   to 1, so the message is an attention-weighted mean; the extra `1/k` only shrank the
//!   initial displacements (and their gradients) 15-fold.
//! - Beyond the thesis, the displacement is bounded: `tanh` (per coordinate) times the
//!   neighbourhood radius `s_i`, so a refined point never leaves its neighbourhood, whatever
//!   the input (no outliers on out-of-distribution clouds).
//! - Centres are processed in chunks, so only `chunk × k × C` gathered features exist at once.

use candle_core::{D, Tensor};
use candle_nn::{Linear, Module, VarBuilder};
use rayon::prelude::*;

use super::RefinementGraph;
use crate::{Error, Result};

/// Centres per chunk (`2048 × 15 × 64` floats ≈ 8 MB of gathered features: below the
/// allocator's 32 MB mmap ceiling, so the chunks reuse heap memory instead of faulting in
/// fresh pages each time, which made a cold 1M-point run's AttRef 2-3× slower).
const CHUNK: usize = 2048;

/// Widths of the layer's parts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AttentionRefinementConfig {
    /// Width C of the embeddings it reads.
    pub channels: usize,
    /// Width d of the query/key projections.
    pub attention_dim: usize,
    /// Hidden units h of φ.
    pub phi_hidden: usize,
    /// Hidden units g of γ.
    pub gamma_hidden: usize,
}

/// The learnable parts of eq. 5.5; parameter names `query`, `key`, `phi.{0,1}`,
/// `gamma.{0,1}`.
#[derive(Clone, Debug)]
pub struct AttentionRefinement {
    query: Linear,
    key: Linear,
    phi: [Linear; 2],
    gamma: [Linear; 2],
    attention_dim: usize,
}

impl AttentionRefinement {
    /// A layer with the widths of `config`.
    ///
    /// ```
    /// use candle_core::{DType, Device, Tensor};
    /// use candle_nn::{VarBuilder, VarMap};
    /// use meshgnn_models::point_simplifier::{
    ///     AttentionRefinement, AttentionRefinementConfig, refinement_graph,
    /// };
    /// let map = VarMap::new();
    /// let vb = VarBuilder::from_varmap(&map, DType::F32, &Device::Cpu);
    /// let cfg = AttentionRefinementConfig { channels: 8, attention_dim: 4, phi_hidden: 6, gamma_hidden: 5 };
    /// let att = AttentionRefinement::new(vb, &cfg)?;
    /// let pts = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    /// let g = refinement_graph(&pts, &[0, 2], 3, &Device::Cpu)?;
    /// let f = Tensor::ones((3, 8), DType::F32, &Device::Cpu)?;
    /// assert_eq!(att.forward(&f, &g)?.dims(), &[2, 3]);
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn new(vb: VarBuilder, config: &AttentionRefinementConfig) -> Result<Self> {
        let AttentionRefinementConfig {
            channels,
            attention_dim,
            phi_hidden,
            gamma_hidden,
        } = *config;
        Ok(Self {
            query: candle_nn::linear(channels, attention_dim, vb.pp("query"))?,
            key: candle_nn::linear(channels, attention_dim, vb.pp("key"))?,
            phi: [
                candle_nn::linear(channels + 3, phi_hidden, vb.pp("phi.0"))?,
                candle_nn::linear(phi_hidden, 3, vb.pp("phi.1"))?,
            ],
            gamma: [
                candle_nn::linear_no_bias(3, gamma_hidden, vb.pp("gamma.0"))?,
                candle_nn::linear_no_bias(gamma_hidden, 3, vb.pp("gamma.1"))?,
            ],
            attention_dim,
        })
    }

    /// From raw parts (tests, hand-set weights): `θ_q`, `θ_k` (both `C → d`), `φ`, `γ`.
    pub fn from_parts(
        query: Linear,
        key: Linear,
        phi: [Linear; 2],
        gamma: [Linear; 2],
    ) -> Result<Self> {
        let attention_dim = query.weight().dim(0)?;
        Ok(Self {
            query,
            key,
            phi,
            gamma,
            attention_dim,
        })
    }

    /// Eq. 5.5 displacements `(M, 3)` of the centres of `graph` from the embeddings of all
    /// input points `features: (N, C)` (differentiable gathers); add them to
    /// `graph.positions`.
    pub fn forward(&self, features: &Tensor, graph: &RefinementGraph) -> Result<Tensor> {
        features.dims2()?;
        self.run(graph, features.device(), |start, len, k| {
            let centres = graph.centres.narrow(0, start, len)?;
            let nb = graph.neighbours.narrow(0, start * k, len * k)?;
            Ok((
                features.index_select(&nb, 0)?,
                features.index_select(&centres, 0)?,
            ))
        })
    }

    /// [`AttentionRefinement::forward`] for inference, from the embeddings as a plain
    /// `features: #N×channels` slice: rows are gathered in parallel Rust (candle's
    /// `index_select` copies row by row), no autograd.
    pub fn forward_host(
        &self,
        features: &[f32],
        channels: usize,
        graph: &RefinementGraph,
    ) -> Result<Tensor> {
        if channels == 0 || !features.len().is_multiple_of(channels) {
            return Err(Error::Invalid {
                what: "AttRef features".into(),
                reason: format!("{} values are not rows of {channels}", features.len()),
            });
        }
        let centres: Vec<u32> = graph.centres.to_vec1()?;
        let neighbours: Vec<u32> = graph.neighbours.to_vec1()?;
        let device = graph.centres.device().clone();
        self.run(graph, &device, |start, len, k| {
            let nb = neighbours.get(start * k..(start + len) * k).unwrap_or(&[]);
            let cs = centres.get(start..start + len).unwrap_or(&[]);
            Ok((
                Tensor::from_vec(
                    gather_rows(features, channels, nb)?,
                    (len * k, channels),
                    &device,
                )?,
                Tensor::from_vec(
                    gather_rows(features, channels, cs)?,
                    (len, channels),
                    &device,
                )?,
            ))
        })
    }

    /// The layer on chunks of centres; `gather(start, len, k)` gives the neighbour features
    /// `(len·k, C)` and centre features `(len, C)` of centres `start..start + len`.
    fn run(
        &self,
        graph: &RefinementGraph,
        device: &candle_core::Device,
        gather: impl Fn(usize, usize, usize) -> Result<(Tensor, Tensor)>,
    ) -> Result<Tensor> {
        let m = graph.centres.dim(0)?;
        if m == 0 {
            return Ok(Tensor::zeros((0, 3), candle_core::DType::F32, device)?);
        }
        let k = graph.k;
        if k == 0 {
            return Err(Error::Invalid {
                what: "refinement graph".into(),
                reason: "has no neighbours per centre".into(),
            });
        }
        let d = self.attention_dim;
        let inv_sqrt_d = 1.0 / (d as f64).sqrt();
        let mut parts = Vec::with_capacity(m.div_ceil(CHUNK).max(1));
        let mut start = 0;
        while start < m {
            let len = CHUNK.min(m - start);
            let off = graph.offsets.narrow(0, start * k, len * k)?;
            let (f_nb, f_c) = gather(start, len, k)?;
            let q = self.query.forward(&f_nb)?.reshape((len, k, d))?;
            let key = self.key.forward(&f_c)?.reshape((len, d, 1))?;
            // the composite softmax (max-shifted exp / sum) is differentiable
            let alpha = candle_nn::ops::softmax(
                &q.matmul(&key)?.reshape((len, k))?.affine(inv_sqrt_d, 0.0)?,
                D::Minus1,
            )?;
            let phi_in = Tensor::cat(&[&f_nb, &off], 1)?;
            let phi = self.phi[1]
                .forward(&self.phi[0].forward(&phi_in)?.relu()?)?
                .reshape((len, k, 3))?;
            let message = phi.broadcast_mul(&alpha.unsqueeze(D::Minus1)?)?.sum(1)?;
            let step = self.gamma[1]
                .forward(&self.gamma[0].forward(&message)?.relu()?)?
                .tanh()?;
            let scales = graph.scales.narrow(0, start, len)?;
            parts.push(step.broadcast_mul(&scales)?);
            start += len;
        }
        Ok(if parts.len() == 1 {
            parts.swap_remove(0)
        } else {
            Tensor::cat(&parts, 0)?
        })
    }
}

/// Rows `indices` of `values: #N×c`, in parallel; an index past N is an error.
fn gather_rows(values: &[f32], c: usize, indices: &[u32]) -> Result<Vec<f32>> {
    let mut out = vec![0f32; indices.len() * c];
    out.par_chunks_mut(c)
        .zip(indices.par_iter())
        .try_for_each(|(row, &i)| {
            let src = values
                .get(i as usize * c..(i as usize + 1) * c)
                .ok_or_else(|| Error::Invalid {
                    what: format!("AttRef neighbour {i}"),
                    reason: format!("out of range for {} feature rows", values.len() / c),
                })?;
            row.copy_from_slice(src);
            Ok::<(), Error>(())
        })?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::point_simplifier::refinement_graph;
    use candle_core::{DType, Device};

    fn lin(w: &[&[f32]], dev: &Device) -> Linear {
        let rows = w.len();
        let cols = w.first().map_or(0, |r| r.len());
        let flat: Vec<f32> = w.iter().flat_map(|r| r.iter().copied()).collect();
        Linear::new(Tensor::from_vec(flat, (rows, cols), dev).unwrap(), None)
    }

    fn cloud() -> Vec<[f32; 3]> {
        // points in the positive octant around centre 0, so every offset is non-negative
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 2.0, 0.0],
            [0.0, 0.0, 3.0],
            [1.0, 1.0, 1.0],
            [9.0, 9.0, 9.0],
        ]
    }

    #[test]
    fn uniform_attention_gives_the_mean_offset_over_k() {
        let dev = Device::Cpu;
        let c = 2; // embedding channels
        // θ_q = 0 → all scores 0 → α = 1/k; φ passes the offset through (ReLU keeps ≥ 0);
        // γ = identity → Δ = s · tanh(mean_j (p_j − p_c) / s).
        let zero_q = lin(&[&[0.0, 0.0]], &dev);
        let key = lin(&[&[1.0, -1.0]], &dev);
        let phi0 = lin(
            &[
                &[0.0, 0.0, 1.0, 0.0, 0.0],
                &[0.0, 0.0, 0.0, 1.0, 0.0],
                &[0.0, 0.0, 0.0, 0.0, 1.0],
            ],
            &dev,
        );
        let id3 = || {
            lin(
                &[&[1.0, 0.0, 0.0], &[0.0, 1.0, 0.0], &[0.0, 0.0, 1.0]],
                &dev,
            )
        };
        let att =
            AttentionRefinement::from_parts(zero_q, key, [phi0, id3()], [id3(), id3()]).unwrap();
        let pts = cloud();
        let k = 5;
        let g = refinement_graph(&pts, &[0], k, &dev).unwrap();
        let f = Tensor::rand(0.0f32, 1.0, (pts.len(), c), &dev).unwrap();
        let delta: Vec<Vec<f32>> = att.forward(&f, &g).unwrap().to_vec2().unwrap();
        // neighbours of 0: itself, (1,0,0), (1,1,1), (0,2,0), (0,0,3): mean (0.4, 0.6, 0.8)
        let s = ((1.0f32 + 4.0 + 9.0 + 3.0) / 5.0).sqrt();
        let want = [0.4f32, 0.6, 0.8].map(|m| s * (m / s).tanh());
        for (a, b) in delta[0].iter().zip(want) {
            assert!((a - b).abs() < 1e-5, "{delta:?}");
        }
    }

    #[test]
    fn zero_phi_gives_zero_displacement() {
        let dev = Device::Cpu;
        let map = candle_nn::VarMap::new();
        let vb = VarBuilder::from_varmap(&map, DType::F32, &dev);
        let cfg = AttentionRefinementConfig {
            channels: 4,
            attention_dim: 3,
            phi_hidden: 5,
            gamma_hidden: 6,
        };
        let random = AttentionRefinement::new(vb, &cfg).unwrap();
        let zero_phi1 = Linear::new(
            Tensor::zeros((3, 5), DType::F32, &dev).unwrap(),
            Some(Tensor::zeros(3, DType::F32, &dev).unwrap()),
        );
        let att = AttentionRefinement::from_parts(
            random.query.clone(),
            random.key.clone(),
            [random.phi[0].clone(), zero_phi1],
            random.gamma.clone(),
        )
        .unwrap();
        let pts = cloud();
        let g = refinement_graph(&pts, &[0, 3, 5], 4, &dev).unwrap();
        let f = Tensor::rand(-1.0f32, 1.0, (pts.len(), 4), &dev).unwrap();
        let delta: Vec<f32> = att
            .forward(&f, &g)
            .unwrap()
            .flatten_all()
            .unwrap()
            .to_vec1()
            .unwrap();
        assert_eq!(delta, vec![0.0; 9]);
        // the inference path (host gathers) gives the same displacements
        let host: Vec<f32> = f.flatten_all().unwrap().to_vec1().unwrap();
        let a: Vec<f32> = random
            .forward(&f, &g)
            .unwrap()
            .flatten_all()
            .unwrap()
            .to_vec1()
            .unwrap();
        let b: Vec<f32> = random
            .forward_host(&host, 4, &g)
            .unwrap()
            .flatten_all()
            .unwrap()
            .to_vec1()
            .unwrap();
        assert_eq!(a, b);
        assert!(random.forward_host(&host[..8], 4, &g).is_err());
        // and the random layer does move them
        let moved: Vec<f32> = random
            .forward(&f, &g)
            .unwrap()
            .flatten_all()
            .unwrap()
            .to_vec1()
            .unwrap();
        assert!(moved.iter().any(|&x| x != 0.0));
    }

    #[test]
    fn attention_follows_the_scores() {
        // θ_q picks feature 0, θ_k = 100 → α concentrates on the neighbour with the largest
        // feature 0; φ = offset; γ = identity → Δ ≈ s · tanh(offset_of_that_neighbour / s).
        let dev = Device::Cpu;
        let att = AttentionRefinement::from_parts(
            lin(&[&[1.0, 0.0]], &dev),
            Linear::new(
                Tensor::new(&[[0.0f32, 0.0]], &dev).unwrap(),
                Some(Tensor::new(&[100.0f32], &dev).unwrap()),
            ),
            [
                lin(
                    &[
                        &[0.0, 0.0, 1.0, 0.0, 0.0],
                        &[0.0, 0.0, 0.0, 1.0, 0.0],
                        &[0.0, 0.0, 0.0, 0.0, 1.0],
                    ],
                    &dev,
                ),
                lin(
                    &[&[1.0, 0.0, 0.0], &[0.0, 1.0, 0.0], &[0.0, 0.0, 1.0]],
                    &dev,
                ),
            ],
            [
                lin(
                    &[&[1.0, 0.0, 0.0], &[0.0, 1.0, 0.0], &[0.0, 0.0, 1.0]],
                    &dev,
                ),
                lin(
                    &[&[1.0, 0.0, 0.0], &[0.0, 1.0, 0.0], &[0.0, 0.0, 1.0]],
                    &dev,
                ),
            ],
        )
        .unwrap();
        let pts = cloud();
        let mut feat = vec![0f32; pts.len() * 2];
        feat[3 * 2] = 1.0; // point 3 = (0, 0, 3) gets the high score
        let f = Tensor::from_vec(feat, (pts.len(), 2), &dev).unwrap();
        let g = refinement_graph(&pts, &[0], 5, &dev).unwrap();
        let delta: Vec<Vec<f32>> = att.forward(&f, &g).unwrap().to_vec2().unwrap();
        let s = ((1.0f32 + 4.0 + 9.0 + 3.0) / 5.0).sqrt();
        assert!(
            (delta[0][2] - s * (3.0 / s).tanh()).abs() < 1e-3,
            "{delta:?}"
        );
        assert!(delta[0][0].abs() < 1e-3 && delta[0][1].abs() < 1e-3);
    }
}
