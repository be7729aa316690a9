//! "Handy++" and "Handy", the hand models of thesis ch. 3, in one place: the spiral
//! autoencoder (`spiral`: layers, model file, training), the PCA baseline (eq. 3.2), the
//! morphable-model trait both implement, the latent Gaussian, scan fitting (ch. 3.4.4), the
//! evaluation metrics and the Table 3.2 / 3.5 protocol, and the hand model file `handy`
//! reads.

mod hand_evaluation;
mod hand_model;
mod latent_gaussian;
mod latent_interpolation;
mod morphable_evaluation;
mod morphable_model;
mod partial_scan;
mod pca;
mod scan_distances;
mod scan_fitting;
mod scan_orientation;
mod shape_batches;
pub mod spiral;

pub use hand_evaluation::{
    FIT_SURFACE_SAMPLES, FitFigures, HandEvaluation, HandEvaluationOptions, HandSplits,
    ScanFitting, evaluate_hand_model,
};
pub use hand_model::{HandModel, LATENT_GAUSSIAN_KEY, LoadedHandModel, check_registered};
pub use latent_gaussian::{LATENT_MODES, LatentGaussian};
pub use latent_interpolation::interpolate_shapes;
pub use morphable_evaluation::{
    SPECIFICITY_SAMPLES, generalisation_error, latent_gaussian, specificity_error,
};
pub use morphable_model::MorphableModel;
pub use partial_scan::partial_scan;
pub use pca::{PCA_MODEL_NAME, Pca};
pub use scan_distances::{ScanDistances, scan_distances};
pub use scan_fitting::{ChamferDirection, ScanFit, ScanFitOptions, SimilarityTransform, fit_scan};
pub use shape_batches::{BATCH_SHAPES, decode_latents, encode_shapes, reconstruct_shapes};
