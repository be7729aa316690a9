//! The point cloud simplification report of thesis ch. 5.4-5.5 (Table 5.1): CD, NC, CE, RE,
//! SDM.

use crate::metrics::chamfer::chamfer_distance;
use crate::metrics::curvature_error::features_for;
use crate::metrics::nearest_value_error::nearest_value_error;
use crate::metrics::normal_consistency::{NormalOrientation, normal_consistency};
use crate::metrics::structural_distortion::{SdmParams, structural_distortion};
use crate::{Error, Result};
use meshgnn_geometry::unit_sphere_normalization;

/// Neighbourhood size for the curvature features (eq. 5.1-5.3) of the evaluation.
pub const EVALUATION_CURVATURE_NEIGHBOURS: usize = 16;

/// Most curvature neighbours `k` the evaluation accepts: the features keep `k` neighbour
/// indices per point, so a million-point cloud at the bound already holds 1 GB of them, and
/// neighbourhoods that large average curvature over much of the shape.
pub const MAX_EVALUATION_CURVATURE_NEIGHBOURS: usize = 256;

/// Metrics of a simplified point cloud against its original, both normalised by the original's
/// centroid and bounding-sphere radius.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointCloudEvaluation {
    /// Chamfer distance (eq. 5.6, per-point means of both directions), squared unit-sphere
    /// units.
    pub cd: f64,
    /// Normal consistency (eq. 5.14) of the PCA normals, unoriented, in [0, 2].
    pub nc: f64,
    /// Curvature error CE (eq. 5.8), dimensionless.
    pub ce: f64,
    /// Roughness error RE (ch. 5.4), dimensionless.
    pub re: f64,
    /// Structural distortion SDM (eq. 5.10-5.13, [`super::structural_distortion`]), in [0, 1].
    pub sdm: f64,
}

/// Evaluates `simplified: #P2×3` against `original: #P1×3` on the points themselves (the
/// thesis evaluates clouds directly; no surface to sample). Curvature features come from the
/// geometry crate with `k` neighbours (16 in [`EVALUATION_CURVATURE_NEIGHBOURS`], capped at
/// `#P − 1`) on each cloud; PCA normals are unoriented, so NC uses `1 − |cos|`.
///
/// Fails, naming the `original points` or the `simplified points`, when a cloud has fewer
/// than 3 points or holds non-finite coordinates; fails on `k` outside
/// `2..=`[`MAX_EVALUATION_CURVATURE_NEIGHBOURS`].
///
/// ```
/// use meshgnn_geometry::icosphere;
/// use meshgnn_losses::metrics::point_cloud_evaluation;
/// let p = icosphere(3).vertices().to_vec();
/// let e = point_cloud_evaluation(&p, &p, 16)?;
/// assert!(e.cd == 0.0 && e.ce == 0.0 && e.re == 0.0);
/// assert!(e.nc < 1e-12 && e.sdm < 1e-9); // 0 up to rounding
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn point_cloud_evaluation(
    original: &[[f32; 3]],
    simplified: &[[f32; 3]],
    k: usize,
) -> Result<PointCloudEvaluation> {
    let norm = unit_sphere_normalization(original).map_err(|error| Error::GeometryOf {
        what: "original points",
        error,
    })?;
    let a = norm.apply(original);
    let b = norm.apply(simplified);
    let (fa, fb) = rayon::join(
        || features_for("original points", &a, k),
        || features_for("simplified points", &b, k),
    );
    let (fa, fb) = (fa?, fb?);
    Ok(PointCloudEvaluation {
        cd: chamfer_distance(&a, &b)?.symmetric_mean(),
        nc: normal_consistency(
            &a,
            &fa.normals,
            &b,
            &fb.normals,
            NormalOrientation::Unoriented,
        )?,
        ce: nearest_value_error(&a, &fa.mean_curvature, &b, &fb.mean_curvature)?,
        re: nearest_value_error(&a, &fa.roughness, &b, &fb.roughness)?,
        sdm: structural_distortion(
            &a,
            &fa.mean_curvature,
            &b,
            &fb.mean_curvature,
            SdmParams::default(),
        )?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::{curvature_error, roughness_error};
    use meshgnn_geometry::{icosphere, sample_surface, subdivided_cube};
    use rand::seq::index::sample;
    use rand::{SeedableRng, rngs::StdRng};

    /// A curved shape with sharp features: the cube's surface, densely sampled.
    fn curved_cloud() -> Vec<[f32; 3]> {
        sample_surface(&subdivided_cube(8), 8000, 3).unwrap().points
    }

    fn subset(points: &[[f32; 3]], fraction: f64, seed: u64) -> Vec<[f32; 3]> {
        let mut rng = StdRng::seed_from_u64(seed);
        let n = (points.len() as f64 * fraction) as usize;
        let mut idx = sample(&mut rng, points.len(), n).into_vec();
        idx.sort_unstable();
        idx.into_iter()
            .filter_map(|i| points.get(i).copied())
            .collect()
    }

    #[test]
    fn random_five_percent_scores_worse_than_the_full_shape() {
        let full = curved_cloud();
        let five = subset(&full, 0.05, 11);
        let half = subset(&full, 0.5, 12);
        let e_full = point_cloud_evaluation(&full, &full, 16).unwrap();
        let e_five = point_cloud_evaluation(&full, &five, 16).unwrap();
        let e_half = point_cloud_evaluation(&full, &half, 16).unwrap();
        assert!(e_full.sdm < 1e-9 && e_full.ce == 0.0 && e_full.re == 0.0);
        for (name, five, half) in [
            ("cd", e_five.cd, e_half.cd),
            ("ce", e_five.ce, e_half.ce),
            ("re", e_five.re, e_half.re),
            ("sdm", e_five.sdm, e_half.sdm),
        ] {
            assert!(five > half && half > 0.0, "{name}: 5% {five} vs 50% {half}");
        }
    }

    #[test]
    fn ce_and_re_agree_with_the_standalone_metrics() {
        let full = curved_cloud();
        let five = subset(&full, 0.05, 5);
        let e = point_cloud_evaluation(&full, &five, 16).unwrap();
        // the cube spans [-1, 1]^3: centroid ≈ 0, radius ≈ √3; curvature is scale-invariant
        let ce = curvature_error(&full, &five, 16).unwrap();
        let re = roughness_error(&full, &five, 16).unwrap();
        assert!((e.ce - ce).abs() < 1e-4 * ce.max(1e-6), "{} vs {ce}", e.ce);
        assert!((e.re - re).abs() < 1e-4 * re.max(1e-6), "{} vs {re}", e.re);
    }

    #[test]
    fn bad_inputs_are_named() {
        let p = icosphere(2).vertices().to_vec();
        let message =
            |a: &[[f32; 3]], b: &[[f32; 3]], k: usize| match point_cloud_evaluation(a, b, k) {
                Ok(_) => String::new(),
                Err(e) => e.to_string(),
            };
        assert_eq!(message(&[], &p, 16), "original points: points is empty");
        assert_eq!(message(&p, &[], 16), "simplified points is empty");
        assert_eq!(
            message(&p, &p[..2], 16),
            "invalid simplified points: curvature needs at least 3 points, got 2"
        );
        assert_eq!(
            message(&p, &p, 0),
            "invalid k: curvature needs 2 to 256 neighbours, got 0"
        );
        assert!(message(&p, &p, MAX_EVALUATION_CURVATURE_NEIGHBOURS + 1).contains("got 257"));
    }

    #[test]
    fn order_invariance() {
        // random samples: no ties among k-NN distances (a regular grid has them, and tie
        // breaking by index would legitimately change the curvature neighbourhoods)
        let p = sample_surface(&icosphere(3), 3000, 9).unwrap().points;
        let q = subset(&p, 0.3, 2);
        let mut q2 = q.clone();
        q2.reverse();
        let e1 = point_cloud_evaluation(&p, &q, 16).unwrap();
        let e2 = point_cloud_evaluation(&p, &q2, 16).unwrap();
        assert!((e1.cd - e2.cd).abs() < 1e-12);
        assert!((e1.ce - e2.ce).abs() < 1e-9);
        assert!((e1.sdm - e2.sdm).abs() < 1e-9);
    }
}
