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
use super::fused_projector::HostAffine;
use crate::{Error, Result};

/// Centres per chunk of the candle path (`2048 × 15 × 64` floats ≈ 8 MB of gathered
/// features: temporaries under the allocator's 32 MB mmap ceiling reuse heap memory instead of
/// faulting in fresh pages each chunk).
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
    /// `features: #N×channels` slice, as fused host loops: each centre's queries, scores,
    /// `φ` messages and `γ` step stay in registers and L1 (no `M·k × C` gathered tensors),
    /// centres in parallel, row kernels dispatched per instruction set as the projector's.
    /// No autograd. Equals [`AttentionRefinement::forward`] up to float rounding (tested).
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
        let rows = features.len() / channels;
        let centres: Vec<u32> = graph.centres.to_vec1()?;
        let neighbours: Vec<u32> = graph.neighbours.to_vec1()?;
        if let Some(&bad) = centres
            .iter()
            .chain(&neighbours)
            .find(|&&i| i as usize >= rows)
        {
            return Err(Error::Invalid {
                what: format!("AttRef neighbour {bad}"),
                reason: format!("out of range for {rows} feature rows"),
            });
        }
        let offsets: Vec<f32> = graph.offsets.flatten_all()?.to_vec1()?;
        let scales: Vec<f32> = graph.scales.flatten_all()?.to_vec1()?;
        let m = centres.len();
        let k = graph.k;
        let device = graph.centres.device();
        if m == 0 {
            return Ok(Tensor::zeros((0, 3), candle_core::DType::F32, device)?);
        }
        if k == 0 || neighbours.len() != m * k || offsets.len() != m * k * 3 || scales.len() != m {
            return Err(Error::Invalid {
                what: "refinement graph".into(),
                reason: format!("{k} neighbours per centre do not fit its {m} centres"),
            });
        }
        let layers = HostLayers::new(self)?;
        if layers.query.input() != channels || layers.phi[0].input() != channels + 3 {
            return Err(Error::Invalid {
                what: "AttRef features".into(),
                reason: format!("{channels} channels for a layer built for another width"),
            });
        }
        let arch = pulp::Arch::new();
        let mut steps = vec![0f32; m * 3];
        steps
            .par_chunks_mut(HOST_CHUNK * 3)
            .enumerate()
            .for_each(|(chunk, out)| {
                let first = chunk * HOST_CHUNK;
                arch.dispatch(HostCentres {
                    layers: &layers,
                    features,
                    channels,
                    k,
                    centres: &centres[first..first + out.len() / 3],
                    neighbours: &neighbours[first * k..],
                    offsets: &offsets[first * k * 3..],
                    scales: &scales[first..],
                    out,
                })
            });
        Ok(Tensor::from_vec(steps, (m, 3), device)?)
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

/// Centres per parallel task of [`AttentionRefinement::forward_host`].
const HOST_CHUNK: usize = 256;

/// The layer's linear maps packed for row-at-a-time products.
struct HostLayers {
    query: HostAffine,
    key: HostAffine,
    phi: [HostAffine; 2],
    gamma: [HostAffine; 2],
    inv_sqrt_d: f32,
}

impl HostLayers {
    fn new(layer: &AttentionRefinement) -> Result<Self> {
        let pack = HostAffine::from_linear;
        Ok(Self {
            query: pack(&layer.query)?,
            key: pack(&layer.key)?,
            phi: [pack(&layer.phi[0])?, pack(&layer.phi[1])?],
            gamma: [pack(&layer.gamma[0])?, pack(&layer.gamma[1])?],
            inv_sqrt_d: (1.0 / (layer.attention_dim as f64).sqrt()) as f32,
        })
    }
}

/// Eq. 5.5 for a run of centres: `out: #centres × 3` gets `s_i · tanh(γ(Σ_j α_ij φ_j))`.
struct HostCentres<'a> {
    layers: &'a HostLayers,
    features: &'a [f32],
    channels: usize,
    k: usize,
    centres: &'a [u32],
    /// From the run's first centre on, `k` per centre.
    neighbours: &'a [u32],
    /// From the run's first centre on, `3k` per centre.
    offsets: &'a [f32],
    /// From the run's first centre on.
    scales: &'a [f32],
    out: &'a mut [f32],
}

impl pulp::WithSimd for HostCentres<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        let Self {
            layers,
            features,
            channels: c,
            k,
            ..
        } = self;
        let row = |i: u32| &features[i as usize * c..(i as usize + 1) * c];
        let d = layers.key.output();
        let h = layers.phi[0].output();
        let mut key = vec![0f32; d];
        let mut query = vec![0f32; k * d];
        let mut phi_in = vec![0f32; k * (c + 3)];
        let mut hidden = vec![0f32; k * h];
        let mut messages = vec![0f32; k * 3];
        let mut scores = vec![0f32; k];
        let mut gamma_hidden = vec![0f32; layers.gamma[0].output()];
        for (r, (out, &centre)) in self.out.chunks_exact_mut(3).zip(self.centres).enumerate() {
            layers.key.apply(row(centre), &mut key);
            // φ's inputs `[f_j ‖ offset_j]`, one row per neighbour; θ_q reads their `f_j`
            for ((input, &j), offset) in phi_in
                .chunks_exact_mut(c + 3)
                .zip(&self.neighbours[r * k..(r + 1) * k])
                .zip(self.offsets[r * k * 3..(r + 1) * k * 3].chunks_exact(3))
            {
                input[..c].copy_from_slice(row(j));
                input[c..].copy_from_slice(offset);
            }
            layers.query.apply_strided(&phi_in, c + 3, &mut query);
            for (s, q) in scores.iter_mut().zip(query.chunks_exact(d)) {
                let dot: f32 = q.iter().zip(&key).map(|(a, b)| a * b).sum();
                *s = dot * layers.inv_sqrt_d;
            }
            layers.phi[0].apply_strided(&phi_in, c + 3, &mut hidden);
            for v in hidden.iter_mut() {
                *v = v.max(0.0);
            }
            layers.phi[1].apply_strided(&hidden, h, &mut messages);
            // softmax over the neighbours, max-shifted
            let max = scores.iter().fold(f32::NEG_INFINITY, |a, &b| a.max(b));
            let mut total = 0f32;
            for s in scores.iter_mut() {
                *s = (*s - max).exp();
                total += *s;
            }
            let mut message = [0f32; 3];
            for (s, m) in scores.iter().zip(messages.chunks_exact(3)) {
                for (acc, &v) in message.iter_mut().zip(m) {
                    *acc += s / total * v;
                }
            }
            layers.gamma[0].apply(&message, &mut gamma_hidden);
            for h in gamma_hidden.iter_mut() {
                *h = h.max(0.0);
            }
            layers.gamma[1].apply(&gamma_hidden, out);
            let scale = self.scales[r];
            for v in out.iter_mut() {
                *v = v.tanh() * scale;
            }
        }
    }
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
    fn host_loops_equal_the_candle_layer() {
        // random weights and embeddings, centres with coincident neighbours (s = 0) included
        let dev = Device::Cpu;
        let map = candle_nn::VarMap::new();
        let vb = candle_nn::VarBuilder::from_varmap(&map, DType::F32, &dev);
        let cfg = AttentionRefinementConfig {
            channels: 8,
            attention_dim: 4,
            phi_hidden: 6,
            gamma_hidden: 5,
        };
        let att = AttentionRefinement::new(vb, &cfg).unwrap();
        let mut pts = cloud();
        pts.extend((0..40).map(|i| {
            let t = i as f32 * 0.7;
            [t.sin(), t.cos(), (i % 3) as f32]
        }));
        pts.extend([[5.0, 5.0, 5.0]; 4]);
        let centres: Vec<u32> = (0..pts.len() as u32).step_by(3).collect();
        let g = refinement_graph(&pts, &centres, 4, &dev).unwrap();
        let f = Tensor::randn(0.0f32, 1.0, (pts.len(), 8), &dev).unwrap();
        let want: Vec<Vec<f32>> = att.forward(&f, &g).unwrap().to_vec2().unwrap();
        let host: Vec<f32> = f.flatten_all().unwrap().to_vec1().unwrap();
        let got: Vec<Vec<f32>> = att.forward_host(&host, 8, &g).unwrap().to_vec2().unwrap();
        assert_eq!(got.len(), want.len());
        for (a, b) in got.iter().zip(&want) {
            for (x, y) in a.iter().zip(b) {
                assert!((x - y).abs() <= 1e-5 * (1.0 + y.abs()), "{a:?} vs {b:?}");
            }
        }
        assert!(want.iter().flatten().any(|&v| v != 0.0));
        assert!(att.forward_host(&host[..16], 8, &g).is_err());
        assert!(att.forward_host(&host, 7, &g).is_err());
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
        // Seeded weights and fixed features: with candle's unseeded draws, one run of the
        // suite left this small layer's output all zero and the last check failed.
        crate::spiral::seeded_initialization(&map, 0).unwrap();
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
        let features: Vec<f32> = (0..pts.len() * 4)
            .map(|i| (i as f32 * 0.37).sin())
            .collect();
        let f = Tensor::from_vec(features, (pts.len(), 4), &dev).unwrap();
        let delta: Vec<f32> = att
            .forward(&f, &g)
            .unwrap()
            .flatten_all()
            .unwrap()
            .to_vec1()
            .unwrap();
        assert_eq!(delta, vec![0.0; 9]);
        // the inference path (host loops, summing in another order) gives the same
        // displacements up to rounding
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
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() <= 1e-5 * (1.0 + y.abs()), "{a:?} vs {b:?}");
        }
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
