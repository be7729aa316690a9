//! Input checks shared by every metric and loss: non-empty, finite, matching lengths.

use crate::{Error, Result};

/// Fails with [`Error::Empty`] or [`Error::NonFinite`] unless `points: #P×3` is a non-empty
/// set of finite points.
pub(crate) fn check_points(what: &'static str, points: &[[f32; 3]]) -> Result<()> {
    if points.is_empty() {
        return Err(Error::Empty { what });
    }
    check_finite(what, points)
}

/// Fails with [`Error::NonFinite`] at the first point with a NaN or infinite coordinate.
pub(crate) fn check_finite(what: &'static str, points: &[[f32; 3]]) -> Result<()> {
    match meshgnn_geometry::vec3::first_non_finite(points) {
        Some(index) => Err(Error::NonFinite { what, index }),
        None => Ok(()),
    }
}

/// Fails with [`Error::NonFinite`] at the first non-finite scalar.
pub(crate) fn check_scalars(what: &'static str, values: &[f32]) -> Result<()> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(Error::NonFinite { what, index }),
        None => Ok(()),
    }
}

/// Fails with [`Error::LengthMismatch`] unless `actual == expected`.
pub(crate) fn check_len(what: &'static str, expected: usize, actual: usize) -> Result<()> {
    if expected == actual {
        Ok(())
    } else {
        Err(Error::LengthMismatch {
            what,
            expected,
            actual,
        })
    }
}

/// Fails with [`Error::IndexOutOfRange`] at the first face referring to a vertex `>= count`.
#[cfg(feature = "candle")]
pub(crate) fn check_faces(what: &'static str, faces: &[[u32; 3]], count: usize) -> Result<()> {
    for (index, f) in faces.iter().enumerate() {
        if let Some(&value) = f.iter().find(|&&v| v as usize >= count) {
            return Err(Error::IndexOutOfRange {
                what,
                index,
                value: u64::from(value),
                count,
            });
        }
    }
    Ok(())
}
