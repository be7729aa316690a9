//! The crate's error type.

use std::path::PathBuf;

/// Everything that can go wrong building, training, saving or running a model.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A tensor operation failed (shape mismatch, dtype, device).
    #[error("tensor operation failed: {0}")]
    Candle(#[from] candle_core::Error),
    /// A graph operator (spirals, hierarchy, k-NN, FPS) rejected its input.
    #[error(transparent)]
    Graph(#[from] meshgnn_graph::Error),
    /// A geometry operator or reader rejected its input.
    #[error(transparent)]
    Geometry(#[from] meshgnn_geometry::Error),
    /// A loss or metric rejected its input.
    #[error(transparent)]
    Losses(#[from] meshgnn_losses::Error),
    /// A checkpoint file could not be read or written.
    #[error("checkpoint {path}: {reason}")]
    Checkpoint {
        /// The checkpoint file.
        path: PathBuf,
        /// What is wrong with it.
        reason: String,
    },
    /// An argument or input is outside what the model accepts.
    #[error("{what}: {reason}")]
    Invalid {
        /// The argument or input.
        what: String,
        /// What is wrong with it.
        reason: String,
    },
}

/// The crate's result type.
pub type Result<T> = std::result::Result<T, Error>;
