//! The curvature fields of an original and a simplified cloud at the same locations and the
//! same physical scale: what the perceptual metrics of thesis ch. 5.4 (CE eq. 5.8, RE, SDM
//! eq. 5.10-5.13) compare. Choices and their measurements: docs/losses.md, "Fair curvature
//! metrics".
//!
//! # Why
//! Eq. 5.1-5.3 on each cloud's own `k` nearest neighbours measure each cloud at its own
//! spacing, and PCA curvature grows with the square of the neighbourhood radius: a uniform 5%
//! subsample reads about 20× the original's curvature, so the metrics reward selections that
//! keep the original's local density (clusters) and drift with the input's density.
//!
//! # Definition
//! - **Reference.** The original `P1` is represented by `R`: all of it, or a uniform random
//!   subset of [`REFERENCE_OVERSAMPLING`]` × #P2` points when it is larger (seed
//!   [`REFERENCE_SEED`]), so the cost follows the simplified size and a million-point input is
//!   measured in the same time as a 100k one.
//! - **Scale.** One Gaussian kernel radius `ρ` for both clouds, set so that a *uniform* cloud of
//!   `#P2` points on the original's surface holds `k` points within `ρ`: with `h_R` the mean
//!   squared distance from a point of `R` to its `k` nearest (`(k+1)/(2πδ)` for a surface
//!   density `δ`), `ρ² = 2 h_R (#R / #P2) k/(k+1)`. It depends on the surface and `#P2` only,
//!   not on how densely the original was sampled.
//! - **Locations.** Both fields are evaluated at every point of `R` and every point of `P2`
//!   with the geometry crate's `curvature_at_scale`: `K̄_1(q)`, `R_1(q)` from `R`, `K̄_2(q)`,
//!   `R_2(q)` from `P2`, at the same `q`.

use crate::validate::check_points;
use crate::{Error, Result};
use meshgnn_geometry::{CurvatureAtScale, SpatialIndex, curvature_at_scale};
use rand::{SeedableRng, rngs::StdRng, seq::index::sample};

/// The reference keeps at most this many original points per simplified point.
pub const REFERENCE_OVERSAMPLING: usize = 8;

/// Seed of the reference subset (a fixed one: the metric is a function of its inputs).
pub const REFERENCE_SEED: u64 = 0x5eed_c0de;

/// Both clouds' fields of eq. 5.1-5.3 at the reference and at the simplified points.
///
/// The metrics read them: CE and RE compare the two fields at `R` (eq. 5.8 with the simplified
/// field taken at the same location instead of at the nearest simplified point), SDM compares
/// them in both directions ([`super::pc_msdm`]).
#[derive(Debug, Clone, PartialEq)]
pub struct MatchedScaleCurvature {
    /// The original's representative `R` (module docs), `#R×3`.
    pub reference: Vec<[f32; 3]>,
    /// Kernel radius `ρ`, in the clouds' length units.
    pub radius: f64,
    /// The original's fields at `R`.
    pub original_at_reference: CurvatureAtScale,
    /// The simplified cloud's fields at `R`.
    pub simplified_at_reference: CurvatureAtScale,
    /// The original's fields at the simplified points.
    pub original_at_simplified: CurvatureAtScale,
    /// The simplified cloud's fields at its own points.
    pub simplified_at_simplified: CurvatureAtScale,
}

/// The fields of `original: #P1×3` and `simplified: #P2×3` at one scale (module docs), with
/// `k` simplified points per kernel radius multiplied by `scale²` (`scale = 1` is the
/// definition; other values measure the metrics' sensitivity to it). Fails, naming the cloud,
/// on fewer than 3 points or a non-finite one; fails on `k < 2` or a non-positive `scale`.
///
/// ```
/// use meshgnn_geometry::icosphere;
/// use meshgnn_losses::metrics::matched_scale_curvature;
/// let p = icosphere(3).vertices().to_vec();
/// let m = matched_scale_curvature(&p, &p, 16, 1.0)?;
/// assert_eq!(m.original_at_reference, m.simplified_at_reference);
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn matched_scale_curvature(
    original: &[[f32; 3]],
    simplified: &[[f32; 3]],
    k: usize,
    scale: f64,
) -> Result<MatchedScaleCurvature> {
    for (what, points) in [
        ("original points", original),
        ("simplified points", simplified),
    ] {
        check_points(what, points)?;
        if points.len() < 3 {
            return Err(Error::InvalidParameter {
                name: what,
                message: format!("curvature needs at least 3 points, got {}", points.len()),
            });
        }
    }
    if k < 2 {
        return Err(Error::InvalidParameter {
            name: "k",
            message: format!("the kernel needs at least 2 points, got {k}"),
        });
    }
    let CurvatureReference {
        points: reference,
        radius,
    } = curvature_reference(original, simplified.len(), k, scale)?;
    let queries: Vec<[f32; 3]> = reference.iter().chain(simplified).copied().collect();
    let (of_original, of_simplified) = rayon::join(
        || curvature_at_scale(&reference, &queries, radius),
        || curvature_at_scale(simplified, &queries, radius),
    );
    let split = |all: CurvatureAtScale| {
        let at = |range: std::ops::Range<usize>| CurvatureAtScale {
            curvature: all.curvature[range.clone()].to_vec(),
            mean_curvature: all.mean_curvature[range.clone()].to_vec(),
            roughness: all.roughness[range].to_vec(),
        };
        (at(0..reference.len()), at(reference.len()..queries.len()))
    };
    let (original_at_reference, original_at_simplified) = split(of_original?);
    let (simplified_at_reference, simplified_at_simplified) = split(of_simplified?);
    Ok(MatchedScaleCurvature {
        reference,
        radius,
        original_at_reference,
        simplified_at_reference,
        original_at_simplified,
        simplified_at_simplified,
    })
}

/// The original's side of the comparison: its reference points `R` and the kernel radius `ρ`.
#[derive(Debug, Clone, PartialEq)]
pub struct CurvatureReference {
    /// `R`, `#R×3` (module docs).
    pub points: Vec<[f32; 3]>,
    /// `ρ` times the requested scale.
    pub radius: f64,
}

/// `R` and `ρ` (module docs) for comparing `original: #P1×3` with a cloud of
/// `simplified_count` points, `k` simplified points per radius, the radius multiplied by
/// `scale`: what both the metrics and the training loss (eq. 5.8 at one scale) start from.
/// Fails on fewer than 3 original points or 0 simplified ones, `k < 2` or a `scale` that is
/// not positive and finite.
///
/// ```
/// use meshgnn_geometry::icosphere;
/// use meshgnn_losses::metrics::curvature_reference;
/// let p = icosphere(4).vertices().to_vec(); // 2 562 points
/// let r = curvature_reference(&p, 100, 16, 1.0)?;
/// assert_eq!(r.points.len(), 800); // 8 × 100
/// // a uniform 100 on the unit sphere hold 16 within ρ: πρ² · 100 / 4π = 16, ρ² = 0.64
/// assert!((r.radius * r.radius / 0.64 - 1.0).abs() < 0.05);
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn curvature_reference(
    original: &[[f32; 3]],
    simplified_count: usize,
    k: usize,
    scale: f64,
) -> Result<CurvatureReference> {
    check_points("original points", original)?;
    if original.len() < 3 || simplified_count == 0 || k < 2 {
        return Err(Error::InvalidParameter {
            name: "curvature reference",
            message: format!(
                "needs 3 original points, 1 simplified and k >= 2, got {}, {simplified_count} and {k}",
                original.len()
            ),
        });
    }
    if !(scale > 0.0 && scale.is_finite()) {
        return Err(Error::InvalidParameter {
            name: "scale",
            message: format!("must be positive and finite, got {scale}"),
        });
    }
    let points = reference_subset(original, simplified_count);
    let radius = scale * kernel_radius(&points, simplified_count, k)?;
    Ok(CurvatureReference { points, radius })
}

/// `( mean_q (a(q) − b(q))² )^{1/2}`: eq. 5.8's RMS of a field difference at shared locations.
pub(crate) fn rms_difference(a: &[f32], b: &[f32]) -> f64 {
    let n = a.len().min(b.len());
    let sum = crate::deterministic_sum::deterministic_sum(n, |i| {
        let d = f64::from(a[i]) - f64::from(b[i]);
        d * d
    });
    if n == 0 { 0.0 } else { (sum / n as f64).sqrt() }
}

/// `R`: the original, or [`REFERENCE_OVERSAMPLING`]` × simplified_count` of its points drawn
/// uniformly without replacement, in their input order.
fn reference_subset(original: &[[f32; 3]], simplified_count: usize) -> Vec<[f32; 3]> {
    let size = REFERENCE_OVERSAMPLING.saturating_mul(simplified_count);
    if size >= original.len() {
        return original.to_vec();
    }
    let mut rng = StdRng::seed_from_u64(REFERENCE_SEED);
    let mut picked = sample(&mut rng, original.len(), size).into_vec();
    picked.sort_unstable();
    picked.into_iter().map(|i| original[i]).collect()
}

/// `ρ = (2 h_R (#R / #P2) k/(k+1))^{1/2}` (module docs); a tiny positive radius when every point of `R`
/// coincides with its neighbours (all curvature is then 0).
fn kernel_radius(reference: &[[f32; 3]], simplified_count: usize, k: usize) -> Result<f64> {
    let k = k.min(reference.len() - 1);
    let neighbours = SpatialIndex::new(reference)?.knn_graph(k)?;
    let h = crate::deterministic_sum::deterministic_sum(neighbours.squared_distances.len(), |i| {
        f64::from(neighbours.squared_distances[i])
    }) / neighbours.squared_distances.len() as f64;
    let density_ratio = reference.len() as f64 / simplified_count as f64;
    let radius = (2.0 * h * density_ratio * k as f64 / (k + 1) as f64).sqrt();
    Ok(radius.max(1e-150))
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshgnn_geometry::{icosphere, sample_surface};

    #[test]
    fn the_radius_holds_k_simplified_points_whatever_the_original_density() {
        // A unit sphere (area 4π) sampled at two densities, 2 000 simplified points: a uniform
        // cloud of 2 000 holds k = 16 points within ρ when πρ² · 2000 / 4π = 16, ρ² = 0.032
        // (the sampled icosphere's area is within 0.2% of 4π).
        let sphere = icosphere(5);
        let simplified = sample_surface(&sphere, 2_000, 1).unwrap().points;
        for n in [20_000, 200_000] {
            let original = sample_surface(&sphere, n, 2).unwrap().points;
            let m = matched_scale_curvature(&original, &simplified, 16, 1.0).unwrap();
            assert_eq!(m.reference.len(), 16_000);
            let r2 = m.radius * m.radius;
            assert!((r2 / 0.032 - 1.0).abs() < 0.05, "{n}: ρ² = {r2}");
        }
    }

    #[test]
    fn bad_inputs_are_named() {
        let p = icosphere(2).vertices().to_vec();
        let message = |a: &[[f32; 3]], b: &[[f32; 3]], k: usize, s: f64| {
            matched_scale_curvature(a, b, k, s)
                .err()
                .map(|e| e.to_string())
                .unwrap_or_default()
        };
        assert_eq!(message(&[], &p, 16, 1.0), "original points is empty");
        assert_eq!(
            message(&p, &p[..2], 16, 1.0),
            "invalid simplified points: curvature needs at least 3 points, got 2"
        );
        assert!(message(&p, &p, 1, 1.0).contains("k"));
        assert!(message(&p, &p, 16, 0.0).contains("scale"));
    }
}
