//! The one error type of `meshgnn-geometry`.
//!
//! Every variant names what is wrong and where: the file, the element (vertex, face, header
//! line, buffer) and its index, so a user can find the problem without a debugger.

use std::path::PathBuf;

/// Everything that can go wrong in this crate.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The operating system refused to read or write a file.
    #[error("{path}: {error}")]
    Io {
        /// The file being read or written.
        path: PathBuf,
        /// The underlying I/O error (shown in the message, so not repeated as a `source()`).
        error: std::io::Error,
    },

    /// A file's content is malformed: bad header, truncated data, unparsable number, ...
    #[error("{path}: {element}: {message}")]
    Format {
        /// The file (`<memory>` when parsing bytes that came from no file).
        path: PathBuf,
        /// The element at fault, e.g. `header line 3`, `face 17`, `accessor 2`.
        element: String,
        /// What is wrong with it.
        message: String,
    },

    /// The file extension names no format this crate reads or writes.
    #[error("{path}: unsupported format (expected one of .obj .ply .off .gltf .glb .xyz)")]
    UnsupportedFormat {
        /// The file whose extension was not recognised.
        path: PathBuf,
    },

    /// An index points past the end of the array it refers to.
    #[error("{element} {index} refers to {target} {value}, but there are only {count}")]
    IndexOutOfRange {
        /// Kind of element holding the index, e.g. `triangle`.
        element: &'static str,
        /// Position of that element.
        index: usize,
        /// Kind of element referred to, e.g. `vertex`.
        target: &'static str,
        /// The offending index value.
        value: u64,
        /// How many `target` elements exist.
        count: usize,
    },

    /// A coordinate or attribute is NaN or infinite.
    #[error("{element} {index} has a non-finite value")]
    NonFinite {
        /// Kind of element, e.g. `vertex`, `normal`.
        element: &'static str,
        /// Its position.
        index: usize,
    },

    /// Two arrays that must have the same length do not.
    #[error("{what}: expected {expected} entries, got {actual}")]
    LengthMismatch {
        /// Which array, e.g. `vertex normals`.
        what: &'static str,
        /// The required length.
        expected: usize,
        /// The length given.
        actual: usize,
    },

    /// An operation needs a non-empty input.
    #[error("{what} is empty")]
    Empty {
        /// What was empty, e.g. `point cloud`.
        what: &'static str,
    },

    /// A parameter is outside its valid range.
    #[error("invalid {name}: {message}")]
    InvalidParameter {
        /// Parameter name as the caller wrote it, e.g. `k`.
        name: &'static str,
        /// Why it is invalid and what would be valid.
        message: String,
    },

    /// A numerical solver failed (factorisation of a singular matrix, no convergence).
    #[error("{solver}: {message}")]
    Solver {
        /// Which solver, e.g. `laplacian eigenvectors`.
        solver: &'static str,
        /// What went wrong.
        message: String,
    },

    /// An output path names one of the command's inputs (see `OutputGuard`).
    #[error("refusing to write {output}: it {relation} the input {input}; {fix}")]
    OutputIsInput {
        /// The output as the user gave it.
        output: PathBuf,
        /// The input it would replace.
        input: PathBuf,
        /// How they are the same file, e.g. `is a hard link to`.
        relation: &'static str,
        /// What to do instead.
        fix: String,
    },
}

/// Shorthand for results of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;
