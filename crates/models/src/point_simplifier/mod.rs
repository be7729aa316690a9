//! The learnable point-cloud simplifier of thesis ch. 5: layers, model, selector, loss, what
//! it trains and its checkpoints. See `docs/pcsimplify_model.md`; the bundled default
//! weights load with `crate::pretrained::load("point_simplifier")`.

mod attention_refinement;
mod checkpoint;
mod fused_projector;
mod latent_sampling;
mod mean_aggregation_gnn;
mod neighbour_index;
mod point_mlp;
#[allow(clippy::module_inception)]
mod point_simplifier;
mod refinement_graph;
mod simplifier_loss;
mod simplifier_training;
mod simplify;

pub use attention_refinement::{AttentionRefinement, AttentionRefinementConfig};
pub use checkpoint::POINT_SIMPLIFIER_NAME;
pub use latent_sampling::{LatentSamplingOptions, latent_farthest_point_sampling};
pub use mean_aggregation_gnn::MeanAggregationGnn;
pub use neighbour_index::NeighbourIndex;
pub use point_mlp::PointMlp;
pub use point_simplifier::{
    CENTROIDAL_STEPS, PointSimplifier, PointSimplifierConfig, SelectorSpace, SimplifierOutput,
    StageTimings,
};
pub use refinement_graph::{RefinementGraph, refinement_graph, refinement_graph_indexed};
pub use simplifier_loss::{
    CURVATURE_LOSS_WEIGHT, CurvatureTarget, SimplifierLoss, simplifier_loss,
};
pub use simplifier_training::{
    SimplifierObjective, SimplifierTraining, TrainingSample, VALIDATION_RATIOS,
    prepare_denoising_sample, prepare_training_sample,
};
pub use simplify::{Simplification, SimplifyOptions};
