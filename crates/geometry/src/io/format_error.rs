//! The one constructor of [`Error::Format`] used by every reader, so messages look alike.

use crate::error::Error;
use std::path::Path;

/// Name used in errors for bytes that came from no file.
pub(crate) const MEMORY: &str = "<memory>";

/// An [`Error::Format`] naming the file (or `<memory>`), the element and the problem.
pub(crate) fn format_error(
    path: &Path,
    element: impl Into<String>,
    message: impl Into<String>,
) -> Error {
    Error::Format {
        path: path.to_path_buf(),
        element: element.into(),
        message: message.into(),
    }
}
