//! The one error type of `meshgnn-data`.
//!
//! Every variant names the file or parameter at fault and what is wrong with it.

use std::path::PathBuf;

/// Everything that can go wrong while generating, reading or writing a dataset.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A mesh operation of `meshgnn-geometry` failed (reading, writing, validation).
    #[error(transparent)]
    Geometry(#[from] meshgnn_geometry::Error),

    /// The operating system refused to read or write a file.
    #[error("{path}: {error}")]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The underlying I/O error (shown in the message, so not repeated as a `source()`).
        error: std::io::Error,
    },

    /// A generator parameter is outside its documented range.
    #[error("parameter `{name}` = {value}: {message}")]
    InvalidParameter {
        /// The parameter name, e.g. `count`.
        name: &'static str,
        /// The value given, formatted.
        value: String,
        /// The accepted range or the reason it is rejected.
        message: String,
    },

    /// A mesh or array does not have the topology or size required.
    #[error("{element}: {message}")]
    Topology {
        /// The element at fault, e.g. `quad 12` or `mesh sample_0007.ply`.
        element: String,
        /// What is wrong with it.
        message: String,
    },

    /// A dataset manifest (`dataset.json`) is malformed or inconsistent with the folder.
    #[error("{path}: {message}")]
    Manifest {
        /// The manifest or the file it names.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },

    /// Encoding a PNG preview failed.
    #[error("{path}: PNG encoding failed: {message}")]
    Png {
        /// The PNG file being written.
        path: PathBuf,
        /// The encoder's message.
        message: String,
    },
}

/// `Result` with this crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// An [`Error::InvalidParameter`] for `name = value`.
pub(crate) fn invalid(name: &'static str, value: impl std::fmt::Display, message: &str) -> Error {
    Error::InvalidParameter {
        name,
        value: value.to_string(),
        message: message.to_string(),
    }
}
