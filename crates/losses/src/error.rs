//! The one error type of `meshgnn-losses`.
//!
//! Every variant names the input (`original points`, `triangle probabilities`, ...), the
//! element and what is wrong, so a caller can fix the input without a debugger.

/// Everything that can go wrong in this crate.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// An operation of the geometry crate (curvature, eigenvectors, sampling, ...) failed.
    #[error(transparent)]
    Geometry(#[from] meshgnn_geometry::Error),

    /// A geometry operation failed on one of several inputs; `what` says which (e.g.
    /// `original mesh`), so the caller can name the right file.
    #[error("{what}: {error}")]
    GeometryOf {
        /// Which input, e.g. `simplified mesh`.
        what: &'static str,
        /// The geometry error (shown in the message, so not repeated as a `source()`).
        error: meshgnn_geometry::Error,
    },

    /// An operation of the graph crate (k-NN graphs, sampling, ...) failed.
    #[error(transparent)]
    Graph(#[from] meshgnn_graph::Error),

    /// A tensor operation failed (wrong dtype, device, shape given to candle).
    #[cfg(feature = "candle")]
    #[error("tensor operation: {0}")]
    Tensor(#[from] candle_core::Error),

    /// An input needs at least one element.
    #[error("{what} is empty")]
    Empty {
        /// Which input, e.g. `simplified points`.
        what: &'static str,
    },

    /// A coordinate or value is NaN or infinite.
    #[error("{what}: element {index} is not finite")]
    NonFinite {
        /// Which input.
        what: &'static str,
        /// Index of the offending element.
        index: usize,
    },

    /// Two inputs that must have the same length do not.
    #[error("{what}: expected {expected} entries, got {actual}")]
    LengthMismatch {
        /// Which input, e.g. `normals of the simplified cloud`.
        what: &'static str,
        /// The required length.
        expected: usize,
        /// The length given.
        actual: usize,
    },

    /// A tensor has the wrong shape.
    #[error("{what}: expected shape {expected}, got {actual:?}")]
    Shape {
        /// Which tensor.
        what: &'static str,
        /// The expected shape in words, e.g. `(N, 3)`.
        expected: &'static str,
        /// The dimensions given.
        actual: Vec<usize>,
    },

    /// An index points past the end of the array it refers to.
    #[error("{what}: entry {index} refers to {value}, but there are only {count}")]
    IndexOutOfRange {
        /// Which input holds the index, e.g. `faces`.
        what: &'static str,
        /// Position of the entry.
        index: usize,
        /// The offending index value.
        value: u64,
        /// How many elements exist.
        count: usize,
    },

    /// A parameter is outside its valid range.
    #[error("invalid {name}: {message}")]
    InvalidParameter {
        /// Parameter name as the caller wrote it, e.g. `tau`.
        name: &'static str,
        /// Why it is invalid and what would be valid.
        message: String,
    },
}

/// Shorthand for results of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;
