//! # meshgnn-models
//!
//! The neural models of the thesis "Advances of Graph Neural Networks for 3D shape learning
//! and analysis" on candle (CPU by default, `cuda` feature optional): the hand models of ch. 3
//! (`handy`: the spiral-convolution autoencoder "Handy++" and its PCA baseline) and the
//! learnable point-cloud simplifier of ch. 5 (`point_simplifier`, with the simplification
//! methods it is compared with in `point_selection`), and the neural mesh simplifier of ch. 6
//! (`mesh_simplifier`: built and tested, not yet trained; docs/mesh_simplifier_model.md), and
//! the 4D expression generator of ch. 4 (`expression`, with its blendshape baseline).
//!
//! One convention for every model (docs/architecture.md): a config struct, `new(vb, &cfg)` and
//! `forward`; one training loop ([`training::train`] over a [`training::Trainable`]); one
//! checkpoint layout ([`Checkpoint`], format [`CHECKPOINT_FORMAT`]); one folder of bundled
//! weights loaded by name ([`pretrained::load`]).
#![cfg_attr(not(test), warn(clippy::unwrap_used, clippy::expect_used))]

mod adam;
mod allocator_policy;
mod checkpoint;
mod count_bounds;
mod error;
mod tensor_file;

pub mod expression;
pub mod handy;
pub mod mesh_simplifier;
pub mod point_selection;
pub mod point_simplifier;
pub mod pretrained;
pub mod training;

pub use adam::{Adam, AdamConfig, sorted_vars};
pub use allocator_policy::reuse_freed_memory;
pub use checkpoint::{
    CHECKPOINT_FORMAT, Checkpoint, CheckpointHeader, LoadCheckpoint, OPTIMIZER_PREFIX,
    TrainingState,
};
pub use count_bounds::{
    MAX_BATCH_SIZE, MAX_CLOUDS_PER_SHAPE, MAX_DECODED_SHAPES, MAX_EPOCHS, MAX_FIT_STEPS,
    MAX_LATENT_SIZE, MAX_SPECIFICITY_SAMPLES, MAX_TRAINING_CLOUD_POINTS,
};
pub use error::{Error, Result};
pub use handy::spiral;
pub use handy::{
    BATCH_SHAPES, ChamferDirection, HandModel, LATENT_GAUSSIAN_KEY, LATENT_MODES, LatentGaussian,
    LoadedHandModel, MorphableModel, PCA_MODEL_NAME, Pca, SPECIFICITY_SAMPLES, ScanDistances,
    ScanFit, ScanFitOptions, SimilarityTransform, check_registered, decode_latents, encode_shapes,
    fit_scan, generalisation_error, interpolate_shapes, latent_gaussian, partial_scan,
    reconstruct_shapes, scan_distances, specificity_error,
};
