//! The learnable point-cloud simplifier of thesis ch. 5: layers, model, selector, loss,
//! training loop, checkpoints and the bundled default weights. See `docs/pcsimplify_model.md`.

mod attention_refinement;
mod checkpoint;
mod fused_projector;
mod latent_sampling;
mod mean_aggregation_gnn;
mod neighbour_index;
mod point_mlp;
#[allow(clippy::module_inception)]
mod point_simplifier;
mod pretrained;
mod refinement_graph;
mod simplifier_loss;
mod simplify;
mod training;

pub use attention_refinement::AttentionRefinement;
pub use checkpoint::{Checkpoint, CheckpointState, read_checkpoint, write_checkpoint};
pub use latent_sampling::{LatentSamplingOptions, latent_farthest_point_sampling};
pub use mean_aggregation_gnn::MeanAggregationGnn;
pub use neighbour_index::NeighbourIndex;
pub use point_mlp::PointMlp;
pub use point_simplifier::{
    PointSimplifier, PointSimplifierConfig, SimplifierOutput, StageTimings,
};
pub use pretrained::PRETRAINED_WEIGHTS;
pub use refinement_graph::{RefinementGraph, refinement_graph, refinement_graph_indexed};
pub use simplifier_loss::{CURVATURE_LOSS_WEIGHT, SimplifierLoss, simplifier_loss};
pub use simplify::{Simplification, SimplifyOptions};
pub use training::{
    Trainer, TrainingConfig, TrainingProgress, TrainingSample, VALIDATION_RATIOS,
    prepare_training_sample,
};
