//! The one error type of `meshgnn-graph`.

/// Everything that can go wrong in this crate; each variant names the element and the fix.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// An error from the geometry crate (reading a template, building a mesh).
    #[error(transparent)]
    Geometry(#[from] meshgnn_geometry::Error),

    /// A parameter is outside its valid range.
    #[error("invalid {name}: {message}")]
    InvalidParameter {
        /// Parameter name as the caller wrote it, e.g. `k`.
        name: &'static str,
        /// Why it is invalid and what would be valid.
        message: String,
    },

    /// Two inputs whose sizes must agree do not.
    #[error("{what}: expected {expected}, got {actual}")]
    ShapeMismatch {
        /// Which quantity, e.g. `columns of the dense operand`.
        what: &'static str,
        /// The required size.
        expected: usize,
        /// The size given.
        actual: usize,
    },
}

/// Shorthand for results of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;
