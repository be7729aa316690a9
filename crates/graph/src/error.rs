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

    /// An input that must have elements has none.
    #[error("{what} is empty")]
    Empty {
        /// What was empty, e.g. `mesh (no triangles)`.
        what: &'static str,
    },

    /// A mesh cannot serve an operation: non-manifold, several components, too few vertices.
    #[error("{what}: {message}")]
    UnusableMesh {
        /// Which mesh, e.g. `hierarchy template`, `level 2`.
        what: String,
        /// What is wrong and where (edge, vertex, component) and how to fix it.
        message: String,
    },

    /// An index refers past the end of the array it indexes.
    #[error("{what} {index} is out of range (must be < {len})")]
    IndexOutOfRange {
        /// Which index, e.g. `start point`, `column of triplet 3`.
        what: &'static str,
        /// The index given.
        index: usize,
        /// The length of the indexed array.
        len: usize,
    },

    /// A coordinate or weight is NaN or infinite.
    #[error("{what} {index} is not finite (NaN or infinity); remove or repair it")]
    NonFinite {
        /// Which array, e.g. `point`, `query`.
        what: &'static str,
        /// The element (point, row) holding the value.
        index: usize,
    },

    /// A sampling weight is negative or NaN.
    #[error("weight {index} is {value}; weights must be finite and >= 0")]
    InvalidWeight {
        /// The element whose weight is invalid.
        index: usize,
        /// The weight given.
        value: f32,
    },

    /// An edge is shared by more than two faces, so the neighbourhood has no cyclic order.
    #[error("edge ({a}, {b}) is non-manifold: {faces} incident faces (at most 2 allowed)")]
    NonManifoldEdge {
        /// First vertex of the edge.
        a: u32,
        /// Second vertex of the edge.
        b: u32,
        /// The number of faces on the edge.
        faces: usize,
    },

    /// A vertex's neighbourhood cannot be ordered (isolated, or its fan is not one disk/strip).
    #[error("vertex {vertex}: {message}")]
    UnusableVertex {
        /// The vertex.
        vertex: u32,
        /// What is wrong with its neighbourhood and how to fix it.
        message: String,
    },
}

/// Shorthand for results of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;
