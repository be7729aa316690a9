//! Rust errors as Python exceptions with the CLIs' one-line messages: a file that cannot be
//! opened or written is an `OSError`; every other problem (malformed file, bad array,
//! impossible request) a `ValueError`.

use std::fmt::Display;

use pyo3::PyErr;
use pyo3::exceptions::{PyOSError, PyValueError};

/// A `ValueError` reading `context: error`, or just `error` when `context` is empty.
pub fn value_error(context: &str, error: impl Display) -> PyErr {
    if context.is_empty() {
        PyValueError::new_err(error.to_string())
    } else {
        PyValueError::new_err(format!("{context}: {error}"))
    }
}

/// A geometry error: `OSError` for I/O, else `ValueError` (the message names the file).
pub fn geometry_error(error: meshgnn_geometry::Error) -> PyErr {
    match error {
        meshgnn_geometry::Error::Io { .. } => PyOSError::new_err(error.to_string()),
        other => PyValueError::new_err(other.to_string()),
    }
}
