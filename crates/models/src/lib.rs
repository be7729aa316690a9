//! # meshgnn-models
//!
//! The neural models of the thesis "Advances of Graph Neural Networks for 3D shape learning
//! and analysis" on candle (CPU by default, `cuda` feature optional): the spiral-convolution
//! hand autoencoder "Handy++" with its PCA baseline (ch. 3) and the learnable point-cloud
//! simplifier (ch. 5), their layers, training loops, safetensors checkpoints and the bundled
//! default weights.
//!
//! Models follow the candle-transformers layout: a config struct, `new(vb, &cfg)` and
//! `forward`.
#![cfg_attr(not(test), warn(clippy::unwrap_used, clippy::expect_used))]

mod adam;
mod error;
mod latent_gaussian;
mod latent_interpolation;
mod morphable_evaluation;
mod morphable_model;
mod partial_scan;
mod pca;
mod scan_distances;
mod scan_fitting;
mod shape_batches;
mod tensor_file;

pub mod point_simplifier;
pub mod spiral;

pub use adam::{Adam, AdamConfig, sorted_vars};
pub use error::{Error, Result};
pub use latent_gaussian::LatentGaussian;
pub use latent_interpolation::interpolate_shapes;
pub use morphable_evaluation::{
    SPECIFICITY_SAMPLES, generalisation_error, latent_gaussian, specificity_error,
};
pub use morphable_model::MorphableModel;
pub use partial_scan::partial_scan;
pub use pca::{PCA_FORMAT, Pca};
pub use scan_distances::{ScanDistances, scan_distances};
pub use scan_fitting::{ChamferDirection, ScanFit, ScanFitOptions, SimilarityTransform, fit_scan};
pub use shape_batches::{BATCH_SHAPES, decode_latents, encode_shapes, reconstruct_shapes};
