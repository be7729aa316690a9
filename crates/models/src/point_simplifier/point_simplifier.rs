//! The learnable point-cloud simplifier of thesis ch. 5.3.2 (Potamias, Bouritsas & Zafeiriou
//! 2022, "Revisiting point cloud simplification: a learnable feature preserving approach",
//! ECCV): a projector (3 point-wise MLP layers of 64 channels + one GNN layer eq. 5.4) embeds
//! every point, FPS in that latent space selects the cluster centres, and AttRef (eq. 5.5)
//! displaces them.
//!
//! # Conventions
//! - Points are in the unit-sphere frame of [`meshgnn_geometry::unit_sphere_normalization`]
//!   (training data and [`PointSimplifier::simplify`] normalise; `forward` expects it).
//! - Selection indices are computed without gradient; the selected embeddings are gathered
//!   from the projector output, so the loss reaches every projector weight through AttRef.
//! - Parameter names (the safetensors keys): `projector.mlp.{0,1,2}.{linear,norm}.*`,
//!   `projector.gnn.{centre,neighbour}.*`, `refine.{query,key,phi.0,phi.1,gamma.0,gamma.1}.*`.

use std::time::{Duration, Instant};

use candle_core::{DType, Device, Tensor};
use candle_nn::VarBuilder;
use meshgnn_graph::{
    FpsStart, centroidal_relaxation_indexed, fast_farthest_point_sampling,
    fast_farthest_point_sampling_indexed, fast_farthest_point_sampling_with_owners,
};

use super::fused_projector::FusedProjector;
use super::{
    AttentionRefinement, AttentionRefinementConfig, LatentSamplingOptions, MeanAggregationGnn,
    NeighbourIndex, PointMlp, RefinementGraph, latent_farthest_point_sampling, refinement_graph,
    refinement_graph_indexed,
};
use crate::{Error, Result};

/// The space the selector runs farthest point sampling in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum SelectorSpace {
    /// Over the projector's embeddings (ch. 5.3.2, the thesis): the selection follows the
    /// learned features, but receives no gradient.
    #[default]
    Latent,
    /// Over the positions (exact FPS from the same seeded start); what is learned is AttRef's
    /// refinement of the kept points. Under the metrics at one physical scale any departure
    /// from an even spread costs SDM, CE and RE (docs/pcsimplify_model.md, "Selector space").
    Position,
    /// Over the positions, then [`CENTROIDAL_STEPS`] Lloyd steps snapped back to the input
    /// points ([`meshgnn_graph::centroidal_relaxation`]): evener and centred, and drawn to local
    /// means rather than to FPS's outliers on noisy clouds.
    Centroidal,
}

/// Lloyd steps of [`SelectorSpace::Centroidal`] (3: the third still lowered SDM on the test
/// families, docs/pcsimplify_model.md).
pub const CENTROIDAL_STEPS: usize = 3;

impl SelectorSpace {
    /// The checkpoint value of the `selector` config entry (files without it are latent).
    pub(crate) fn code(self) -> usize {
        match self {
            Self::Latent => 0,
            Self::Position => 1,
            Self::Centroidal => 2,
        }
    }

    /// The space stored as `code`, if any.
    pub(crate) fn from_code(code: usize) -> Option<Self> {
        [Self::Latent, Self::Position, Self::Centroidal]
            .into_iter()
            .find(|s| s.code() == code)
    }
}

/// Hyper-parameters; defaults are the thesis' (ch. 5.6) where it states them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PointSimplifierConfig {
    /// Where the selector runs FPS (latent, the thesis).
    pub selector: SelectorSpace,
    /// Channels of every projector layer (64).
    pub hidden: usize,
    /// Point-wise MLP layers before the GNN (3).
    pub mlp_layers: usize,
    /// k of the projector's k-NN graph (7).
    pub gnn_neighbours: usize,
    /// k of AttRef's centre-to-input graph (15).
    pub refine_neighbours: usize,
    /// Width d of AttRef's query/key projections (not stated in the thesis; 16).
    pub attention_dim: usize,
    /// Hidden units of AttRef's φ (not stated; 32). Its output is 3 ("filter size 3").
    pub phi_hidden: usize,
    /// Hidden units of AttRef's γ (not stated; 16).
    pub gamma_hidden: usize,
}

impl Default for PointSimplifierConfig {
    fn default() -> Self {
        Self {
            selector: SelectorSpace::Latent,
            hidden: 64,
            mlp_layers: 3,
            gnn_neighbours: 7,
            refine_neighbours: 15,
            attention_dim: 16,
            phi_hidden: 32,
            gamma_hidden: 16,
        }
    }
}

impl PointSimplifierConfig {
    /// Every count field by name: checked by [`PointSimplifier::new`], stored in checkpoints
    /// (the selector beside them, as `selector`).
    pub(crate) fn entries(&self) -> [(&'static str, usize); 7] {
        [
            ("hidden", self.hidden),
            ("mlp_layers", self.mlp_layers),
            ("gnn_neighbours", self.gnn_neighbours),
            ("refine_neighbours", self.refine_neighbours),
            ("attention_dim", self.attention_dim),
            ("phi_hidden", self.phi_hidden),
            ("gamma_hidden", self.gamma_hidden),
        ]
    }

    /// Sets the field `name` of [`PointSimplifierConfig::entries`] (unknown names are ignored:
    /// the callers iterate over `entries`).
    pub(crate) fn set_entry(&mut self, name: &str, value: usize) {
        let field = match name {
            "hidden" => &mut self.hidden,
            "mlp_layers" => &mut self.mlp_layers,
            "gnn_neighbours" => &mut self.gnn_neighbours,
            "refine_neighbours" => &mut self.refine_neighbours,
            "attention_dim" => &mut self.attention_dim,
            "phi_hidden" => &mut self.phi_hidden,
            "gamma_hidden" => &mut self.gamma_hidden,
            _ => return,
        };
        *field = value;
    }
}

/// Wall-clock time of each stage of one simplification (the thesis' ch. 5.5 speed split).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StageTimings {
    /// k-NN graph of the projector (or adjacency conversion).
    pub knn: Duration,
    /// Point-wise MLPs and GNN.
    pub projector: Duration,
    /// Latent FPS (including reading the embeddings back).
    pub selector: Duration,
    /// AttRef: its k-NN graph and the layer.
    pub refinement: Duration,
}

/// What [`PointSimplifier::forward`] returns.
#[derive(Clone, Debug)]
pub struct SimplifierOutput {
    /// Simplified points `(M, 3)`, differentiable in the model's weights.
    pub points: Tensor,
    /// Indices of the selected centres in the input, `#M`, distinct.
    pub indices: Vec<u32>,
    /// Stage timings (k-NN: the rows of a lazy k-NN graph found here; building the graph's
    /// index is the caller's).
    pub timings: StageTimings,
}

/// The model: projector, FPS selector (latent or positions), AttRef.
#[derive(Clone, Debug)]
pub struct PointSimplifier {
    config: PointSimplifierConfig,
    mlps: Vec<PointMlp>,
    gnn: MeanAggregationGnn,
    refine: AttentionRefinement,
    device: Device,
}

impl PointSimplifier {
    /// Builds the model with parameters under `vb` (fresh from a `VarMap`, or loaded from a
    /// checkpoint).
    ///
    /// ```
    /// use candle_core::{DType, Device};
    /// use candle_nn::{VarBuilder, VarMap};
    /// use meshgnn_models::point_simplifier::{PointSimplifier, PointSimplifierConfig};
    /// let map = VarMap::new();
    /// let vb = VarBuilder::from_varmap(&map, DType::F32, &Device::Cpu);
    /// let model = PointSimplifier::new(vb, &PointSimplifierConfig::default())?;
    /// assert_eq!(model.config().hidden, 64);
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn new(vb: VarBuilder, config: &PointSimplifierConfig) -> Result<Self> {
        let c = *config;
        for (name, v) in c.entries() {
            if v == 0 {
                return Err(Error::Invalid {
                    what: format!("config.{name}"),
                    reason: "must be at least 1".into(),
                });
            }
        }
        let device = vb.device().clone();
        let pv = vb.pp("projector");
        let mlps = (0..c.mlp_layers)
            .map(|i| {
                let input = if i == 0 { 3 } else { c.hidden };
                PointMlp::new(pv.pp(format!("mlp.{i}")), input, c.hidden)
            })
            .collect::<Result<Vec<_>>>()?;
        let gnn = MeanAggregationGnn::new(pv.pp("gnn"), c.hidden, c.hidden)?;
        let refine = AttentionRefinement::new(
            vb.pp("refine"),
            &AttentionRefinementConfig {
                channels: c.hidden,
                attention_dim: c.attention_dim,
                phi_hidden: c.phi_hidden,
                gamma_hidden: c.gamma_hidden,
            },
        )?;
        Ok(Self {
            config: c,
            mlps,
            gnn,
            refine,
            device,
        })
    }

    /// The hyper-parameters.
    pub fn config(&self) -> &PointSimplifierConfig {
        &self.config
    }

    /// The device the weights live on.
    pub fn device(&self) -> &Device {
        &self.device
    }

    /// The projector: `points: (N, 3)` and their `graph` → embeddings `(N, C)` (3 × MLP, then
    /// eq. 5.4). `train` uses batch statistics in the batch norms.
    pub fn project(&self, points: &Tensor, graph: &NeighbourIndex, train: bool) -> Result<Tensor> {
        let mut x = points.clone();
        for mlp in &self.mlps {
            x = mlp.forward_t(&x, train)?;
        }
        self.gnn.forward(&x, graph)
    }

    /// The projector as fused host loops when nothing needs autograd (evaluation mode, plain
    /// weights on the CPU); `None` otherwise.
    pub(crate) fn fused_projector(&self, train: bool) -> Result<Option<FusedProjector>> {
        if train || !self.device.is_cpu() || self.mlps.iter().any(PointMlp::is_trainable) {
            return Ok(None);
        }
        let layers = self
            .mlps
            .iter()
            .map(PointMlp::host_affine)
            .collect::<Result<Vec<_>>>()?;
        let (centre, neighbour) = self.gnn.host_affines()?;
        Ok(Some(FusedProjector {
            layers,
            centre,
            neighbour,
        }))
    }

    /// The whole model on `points: #N×3` (unit-sphere frame) with its projector `graph`:
    /// keeps `target` points (`1 ≤ target ≤ N`) chosen by the config's selector (`selection`,
    /// `seed`) and refined by AttRef. A `graph` built by [`NeighbourIndex::from_knn_index`]
    /// over these `points` lends its kd-tree to the Lloyd steps and AttRef's queries, and at
    /// inference only the rows AttRef reads are searched. Errors on a bad target, a graph
    /// over a different N or non-finite points.
    pub fn forward(
        &self,
        points: &[[f32; 3]],
        graph: &NeighbourIndex,
        target: usize,
        selection: LatentSamplingOptions,
        seed: u64,
        train: bool,
    ) -> Result<SimplifierOutput> {
        let n = points.len();
        if target == 0 || target > n {
            return Err(Error::Invalid {
                what: "target count".into(),
                reason: format!("must be in 1..={n} for {n} points, got {target}"),
            });
        }
        if graph.len() != n {
            return Err(Error::Invalid {
                what: "projector graph".into(),
                reason: format!("covers {} points, the cloud has {n}", graph.len()),
            });
        }
        if let Some(i) = meshgnn_geometry::vec3::first_non_finite(points) {
            return Err(Error::Invalid {
                what: format!("point {i}"),
                reason: "has a non-finite coordinate".into(),
            });
        }
        let choice = Choice {
            target,
            selection,
            seed,
        };
        match self.fused_projector(train)? {
            Some(fused) => self.forward_fused(&fused, points, graph, &choice),
            None => self.forward_autograd(points, graph, &choice, train),
        }
    }

    /// [`PointSimplifier::forward`] through the candle projector (training, trainable or
    /// non-CPU weights): every point's embedding, differentiable.
    fn forward_autograd(
        &self,
        points: &[[f32; 3]],
        graph: &NeighbourIndex,
        choice: &Choice,
        train: bool,
    ) -> Result<SimplifierOutput> {
        let t0 = Instant::now();
        let input = Tensor::from_slice(points.as_flattened(), (points.len(), 3), &self.device)?;
        let embeddings = self.project(&input, graph, train)?;
        let latent: Vec<f32> = embeddings
            .detach()
            .to_dtype(DType::F32)?
            .flatten_all()?
            .to_vec1()?;
        let t1 = Instant::now();
        let indices = self.select(points, graph, Some(&latent), choice)?;
        let t2 = Instant::now();
        let rgraph = self.refinement_graph(points, graph, &indices)?;
        let displacement = match embeddings.track_op() {
            true => self.refine.forward(&embeddings, &rgraph)?,
            false => self
                .refine
                .forward_host(&latent, self.config.hidden, &rgraph)?,
        };
        Ok(SimplifierOutput {
            points: rgraph.positions.add(&displacement)?,
            indices,
            timings: StageTimings {
                knn: Duration::ZERO,
                projector: t1 - t0,
                selector: t2 - t1,
                refinement: t2.elapsed(),
            },
        })
    }

    /// [`PointSimplifier::forward`] at inference with the fused projector. The point-wise
    /// layers run while farthest point sampling (sequential) holds one core; the GNN layer
    /// runs on the rows the selector needs (the latent selector: all) and those AttRef reads
    /// (position selectors: the kept points' neighbourhoods, about 70% of the points at 5%).
    /// Stage times overlap: `projector` counts the point-wise layers in full.
    fn forward_fused(
        &self,
        fused: &FusedProjector,
        points: &[[f32; 3]],
        graph: &NeighbourIndex,
        choice: &Choice,
    ) -> Result<SimplifierOutput> {
        let n = points.len();
        let c = self.config.hidden;
        let t0 = Instant::now();
        let mut timings = StageTimings::default();
        let (indices, latent, features) = if self.config.selector == SelectorSpace::Latent {
            let features = fused.pointwise(points)?;
            let all: Vec<u32> = (0..n as u32).collect();
            let t = Instant::now();
            let mean = graph.mean_rows(&all)?;
            timings.knn = t.elapsed();
            let latent = fused.aggregate(&features, &mean, &all)?;
            timings.projector = t0.elapsed() - timings.knn;
            let t = Instant::now();
            let indices = self.select(points, graph, Some(&latent), choice)?;
            timings.selector = t.elapsed();
            (indices, Some(latent), features)
        } else {
            let (indices, features) = rayon::join(
                || {
                    let t = Instant::now();
                    let indices = self.select(points, graph, None, choice);
                    (indices, t.elapsed())
                },
                || {
                    let t = Instant::now();
                    (fused.pointwise(points), t.elapsed())
                },
            );
            (timings.selector, timings.projector) = (indices.1, features.1);
            (indices.0?, None, features.0?)
        };
        let t2 = Instant::now();
        let rgraph = self.refinement_graph(points, graph, &indices)?;
        // the support's embeddings, computed here, count as k-NN and projector time
        let mut support_time = Duration::ZERO;
        let displacement = match latent {
            Some(latent) => self.refine.forward_host(&latent, c, &rgraph)?,
            None => {
                let support = rgraph.support()?;
                let t = Instant::now();
                let mean = graph.mean_rows(&support)?;
                let t_mean = t.elapsed();
                let embeddings = fused.aggregate(&features, &mean, &support)?;
                support_time = t.elapsed();
                timings.knn += t_mean;
                timings.projector += support_time - t_mean;
                self.refine
                    .forward_host(&embeddings, c, &rgraph.renumbered(&support)?)?
            }
        };
        timings.refinement = t2.elapsed() - support_time;
        Ok(SimplifierOutput {
            points: rgraph.positions.add(&displacement)?,
            indices,
            timings,
        })
    }

    /// The config's selector on `points` (`latent`: every point's embedding, `#N×C`, which
    /// the latent selector needs).
    fn select(
        &self,
        points: &[[f32; 3]],
        graph: &NeighbourIndex,
        latent: Option<&[f32]>,
        choice: &Choice,
    ) -> Result<Vec<u32>> {
        let start = FpsStart::Seeded(choice.seed);
        Ok(match (self.config.selector, latent) {
            (SelectorSpace::Latent, Some(latent)) => latent_farthest_point_sampling(
                latent,
                self.config.hidden,
                points,
                choice.target,
                choice.selection,
                choice.seed,
            )?,
            (SelectorSpace::Latent, None) => {
                return Err(Error::Invalid {
                    what: "latent selector".into(),
                    reason: "has no embeddings to sample".into(),
                });
            }
            (SelectorSpace::Position, _) => {
                fast_farthest_point_sampling(points, choice.target, start)?
            }
            (SelectorSpace::Centroidal, _) => {
                let (fps, owners) = match graph.knn_index() {
                    Some(index) => {
                        fast_farthest_point_sampling_indexed(index, choice.target, start)?
                    }
                    None => fast_farthest_point_sampling_with_owners(points, choice.target, start)?,
                };
                centroidal_relaxation_indexed(
                    points,
                    graph.knn_index(),
                    &fps,
                    Some(&owners),
                    CENTROIDAL_STEPS,
                )?
            }
        })
    }

    /// AttRef's eq. 5.5 graph of the kept `indices`, over the graph's k-d tree when it has one.
    fn refinement_graph(
        &self,
        points: &[[f32; 3]],
        graph: &NeighbourIndex,
        indices: &[u32],
    ) -> Result<RefinementGraph> {
        let k = self.config.refine_neighbours;
        match graph.knn_index() {
            Some(index) => refinement_graph_indexed(index, points, indices, k, &self.device),
            None => refinement_graph(points, indices, k, &self.device),
        }
    }
}

/// What [`PointSimplifier::forward`] is asked to keep: how many, the latent selector's cell
/// options, the FPS seed.
struct Choice {
    target: usize,
    selection: LatentSamplingOptions,
    seed: u64,
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshgnn_geometry::{SpatialIndex, icosphere, sample_surface};

    #[test]
    fn fused_inference_keeps_the_candle_paths_points() {
        // bundled weights: the fused path (embeddings only where AttRef reads, the lazy k-NN
        // rows, FPS on the shared tree) against the candle projector on the full graph
        let bundled: PointSimplifier = crate::pretrained::load("point_simplifier").unwrap();
        let points = sample_surface(&icosphere(4), 6000, 3).unwrap().points;
        for selector in [SelectorSpace::Centroidal, SelectorSpace::Position] {
            let model = PointSimplifier {
                config: PointSimplifierConfig {
                    selector,
                    ..bundled.config
                },
                ..bundled.clone()
            };
            let index = SpatialIndex::new(&points).unwrap();
            let lazy = NeighbourIndex::from_knn_index(index, 7, &Device::Cpu).unwrap();
            let choice = Choice {
                target: 300,
                selection: LatentSamplingOptions::default(),
                seed: 4,
            };
            let fused = model.fused_projector(false).unwrap().unwrap();
            let got = model
                .forward_fused(&fused, &points, &lazy, &choice)
                .unwrap();
            let full = NeighbourIndex::from_knn(
                &meshgnn_graph::knn_graph(&points, 7).unwrap(),
                &Device::Cpu,
            )
            .unwrap();
            let want = model
                .forward_autograd(&points, &full, &choice, false)
                .unwrap();
            assert_eq!(got.indices, want.indices, "{selector:?}");
            let (a, b): (Vec<Vec<f32>>, Vec<Vec<f32>>) = (
                got.points.to_vec2().unwrap(),
                want.points.to_vec2().unwrap(),
            );
            let moved = a
                .iter()
                .zip(&points_at(&points, &got.indices))
                .map(|(p, q)| (0..3).map(|d| (p[d] - q[d]).abs()).fold(0.0, f32::max))
                .fold(0.0, f32::max);
            assert!(moved > 0.0, "AttRef moves the points");
            for (p, q) in a.iter().zip(&b) {
                for d in 0..3 {
                    assert!((p[d] - q[d]).abs() <= 1e-5, "{p:?} vs {q:?}");
                }
            }
        }
    }

    fn points_at(points: &[[f32; 3]], indices: &[u32]) -> Vec<[f32; 3]> {
        indices.iter().map(|&i| points[i as usize]).collect()
    }
}
