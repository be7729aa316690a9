//! The neural mesh simplifier of thesis ch. 6 (a learnable point sampler, an edge predictor
//! and a face classifier, trained end to end): the DevConv layer (eq. 6.1) on fixed-width
//! neighbour slots, the point sampler (ch. 6.3.1), the edge predictor with its candidate
//! triangles (ch. 6.3.2, eq. 6.2-6.5), the face classifier with its TriConv layer (ch. 6.3.3,
//! eq. 6.6-6.7), the model that chains them with the final manifold pass, the eq. 6.14
//! objective of one pass, and the supervised training that replaces it (Voronoi-dual targets
//! for edges and faces, QEM importance for the sampler: [`SimplifierTraining`]). Bundled
//! weights: `pretrained::load("neural_mesh_simplifier")`; apps: `meshsimplify simplify
//! --method neural`, `pcsimplify simplify --method sampler` (the point sampler alone).

mod candidate_features;
mod checkpoint;
mod column_concat;
mod dev_conv;
mod dual_targets;
mod edge_predictor;
mod extended_graph;
mod face_classifier;
mod face_graph;
mod flat_rows;
mod incoming_links;
mod island_seeded_draw;
mod linear_relu;
mod link_message_mean;
mod neighbour_deviation_maximum;
mod neighbour_slots;
mod neural_mesh_simplifier;
mod op_operands;
mod point_sampler;
mod simplification_loss;
mod simplified_adjacency;
mod simplifier_training;
mod slot_dot_products;
mod surface_patch;
mod tri_conv;

pub use candidate_features::{CANDIDATE_FEATURES, candidate_features};
pub use checkpoint::NEURAL_MESH_SIMPLIFIER_NAME;
pub use column_concat::column_concat;
pub use dev_conv::{DevConv, DevConvConfig};
pub use dual_targets::DualTargets;
pub use edge_predictor::{CandidateFaces, EdgePrediction, EdgePredictor, EdgePredictorConfig};
pub use extended_graph::ExtendedGraph;
pub use face_classifier::{FaceClassifier, FaceClassifierConfig};
pub use face_graph::FaceGraph;
pub use island_seeded_draw::{ISLAND_FRACTION, with_island_seeds};
pub use linear_relu::linear_relu;
pub use link_message_mean::link_message_mean;
pub use neighbour_deviation_maximum::neighbour_deviation_maximum;
pub use neighbour_slots::NeighbourSlots;
pub use neural_mesh_simplifier::{
    FACE_THRESHOLD, MAX_CRACK_EDGES, MAX_REBUILT_PART_VERTICES, MAX_SURFACE_CRACK_EDGES,
    MAX_WIDE_CRACK_EDGES, MIN_NEURAL_FACES, MIN_WIDE_CRACK_PIECE_FACES, MeshInput,
    NeuralMeshSimplifier, NeuralMeshSimplifierConfig, NeuralSimplification, NeuralSimplifyOptions,
    SAMPLER_CLOUD_NEIGHBOURS, SEED_EXCHANGE_ROUNDS, SimplifierPass,
};
pub use point_sampler::{PointSampler, PointSamplerConfig, SampledPoints};
pub use simplification_loss::{
    PENALTY_NEIGHBOURS, SimplificationTarget, simplification_loss, simplification_terms,
};
pub use simplifier_training::{
    SimplifierExample, SimplifierLosses, SimplifierTraining, VALIDATION_RATIOS, qem_importance,
};
pub use slot_dot_products::slot_dot_products;
pub use surface_patch::{SURFACE_PATCH_NORMAL_AGREEMENT, SURFACE_PATCH_TOLERANCE};
pub use tri_conv::{TriConv, TriConvConfig};
