//! Bounds on user-given counts (samples, steps, points, ...): every count a command line or
//! a caller passes is checked against a documented range *before* anything is allocated, so
//! a typo (`--samples 50000000000`) is a one-line error instead of minutes of swapping.
//!
//! Each crate states the maxima of the counts it owns as named constants next to the code
//! that allocates them; [`check_count`] is the one check they all use. The list of every
//! bound, with the memory each one caps, is in docs/security.md (`## Bounds`).

use std::ops::RangeInclusive;

use crate::error::{Error, Result};

/// Most area-weighted surface samples one call of [`crate::sample_surface`] is asked for by
/// the apps (`meshsimplify eval --samples`, scan and training clouds): a sample keeps a
/// position, a normal and a face index (28 bytes) and the metrics build a spatial index over
/// it, so 10 M samples per surface already need about 1 GB for the two surfaces of an
/// evaluation.
pub const MAX_SURFACE_SAMPLES: usize = 10_000_000;

/// Returns `value` when it lies in `allowed`, else [`Error::InvalidParameter`] naming `name`
/// (as the user wrote it, e.g. `--samples`), the range, and `why` the bound exists.
///
/// ```
/// use meshgnn_geometry::check_count;
/// assert_eq!(check_count("--steps", 8, 2..=1000, "one mesh per step")?, 8);
/// let err = check_count("--steps", 100_000, 2..=1000, "one mesh per step").unwrap_err();
/// assert_eq!(
///     err.to_string(),
///     "invalid --steps: 100000 is outside 2..=1000 (one mesh per step)"
/// );
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn check_count(
    name: &'static str,
    value: usize,
    allowed: RangeInclusive<usize>,
    why: &str,
) -> Result<usize> {
    if allowed.contains(&value) {
        Ok(value)
    } else {
        Err(Error::InvalidParameter {
            name,
            message: format!(
                "{value} is outside {}..={} ({why})",
                allowed.start(),
                allowed.end()
            ),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_ends_are_inclusive() {
        assert_eq!(check_count("n", 1, 1..=3, "x").ok(), Some(1));
        assert_eq!(check_count("n", 3, 1..=3, "x").ok(), Some(3));
        assert!(check_count("n", 0, 1..=3, "x").is_err());
        assert!(check_count("n", 4, 1..=3, "x").is_err());
    }
}
