//! The point cloud simplification report of thesis ch. 5.4-5.5 (Table 5.1): CD, NC, CE, RE,
//! SDM, and the earlier SDM variant beside it.

use crate::metrics::chamfer::chamfer_distance;
use crate::metrics::matched_scale_curvature::{matched_scale_curvature, rms_difference};
use crate::metrics::normal_consistency::{NormalOrientation, normal_consistency};
use crate::metrics::pc_msdm::{PcMsdmParams, pc_msdm};
use crate::metrics::structural_distortion::{SdmParams, structural_distortion};
use crate::validate::check_points;
use crate::{Error, Result};
use meshgnn_geometry::{CurvatureFeatures, curvature_features, unit_sphere_normalization};

/// `k` of the evaluation: neighbours of the PCA normals and of the earlier SDM variant's
/// features, and simplified points per kernel radius of the curvature fields.
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
    /// Curvature error CE (eq. 5.8) at one location set and scale for both clouds
    /// ([`super::curvature_error`]), dimensionless.
    pub ce: f64,
    /// Roughness error RE (ch. 5.4), on the same footing ([`super::roughness_error`]).
    pub re: f64,
    /// Structural distortion SDM (eq. 5.10-5.13) as PC-MSDM defines it, both directions
    /// ([`super::pc_msdm`]), in [0, 1].
    pub sdm: f64,
    /// The earlier SDM variant ([`super::structural_distortion`]: each cloud's curvature at its
    /// own density, the simplified field copied by nearest neighbour, SSIM stabilisers, one
    /// direction), kept beside the new one for comparison.
    pub sdm_nearest: f64,
}

/// Eq. 5.1-5.3 on `points: #P×3` with `k` neighbours, `k` capped at `#P − 1` so that a small
/// simplified cloud still gets features. Fails for fewer than 3 points or `k` outside
/// `2..=MAX_EVALUATION_CURVATURE_NEIGHBOURS`.
fn features_for(what: &'static str, points: &[[f32; 3]], k: usize) -> Result<CurvatureFeatures> {
    check_points(what, points)?;
    if !(2..=MAX_EVALUATION_CURVATURE_NEIGHBOURS).contains(&k) {
        return Err(Error::InvalidParameter {
            name: "k",
            message: format!(
                "curvature needs 2 to {MAX_EVALUATION_CURVATURE_NEIGHBOURS} neighbours, got {k}"
            ),
        });
    }
    if points.len() < 3 {
        return Err(Error::InvalidParameter {
            name: what,
            message: format!("curvature needs at least 3 points, got {}", points.len()),
        });
    }
    Ok(curvature_features(points, k.min(points.len() - 1))?)
}

/// Evaluates `simplified: #P2×3` against `original: #P1×3` on the points themselves (the
/// thesis evaluates clouds directly; no surface to sample). CE, RE and SDM read both clouds'
/// curvature at the same locations and one scale that holds `k` simplified points
/// ([`super::matched_scale_curvature`]); NC and the earlier SDM variant use each cloud's own
/// `k` nearest neighbours (capped at `#P − 1`); PCA normals are unoriented, so NC uses
/// `1 − |cos|`.
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
/// assert!(e.nc < 1e-12 && e.sdm < 1e-12 && e.sdm_nearest < 1e-9); // 0 up to rounding
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn point_cloud_evaluation(
    original: &[[f32; 3]],
    simplified: &[[f32; 3]],
    k: usize,
) -> Result<PointCloudEvaluation> {
    point_cloud_evaluation_at_scale(original, simplified, k, 1.0)
}

/// [`point_cloud_evaluation`] with the curvature kernel radius multiplied by `scale` (1 is the
/// definition; the sensitivity of CE, RE and SDM to it is measured with other values).
/// Fails as [`point_cloud_evaluation`] does, and on a `scale` that is not positive and finite.
///
/// ```
/// use meshgnn_geometry::icosphere;
/// use meshgnn_losses::metrics::{point_cloud_evaluation, point_cloud_evaluation_at_scale};
/// let p = icosphere(3).vertices().to_vec();
/// let q = &p[..200];
/// assert_eq!(point_cloud_evaluation_at_scale(&p, q, 16, 1.0)?, point_cloud_evaluation(&p, q, 16)?);
/// assert!(point_cloud_evaluation_at_scale(&p, q, 16, 0.0).is_err());
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn point_cloud_evaluation_at_scale(
    original: &[[f32; 3]],
    simplified: &[[f32; 3]],
    k: usize,
    scale: f64,
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
    let m = matched_scale_curvature(&a, &b, k, scale)?;
    let params = PcMsdmParams::default();
    let window = 2.0 * m.radius;
    let forward = pc_msdm(
        &m.reference,
        &m.original_at_reference.mean_curvature,
        &m.simplified_at_reference.mean_curvature,
        window,
        params,
    )?;
    let backward = pc_msdm(
        &b,
        &m.simplified_at_simplified.mean_curvature,
        &m.original_at_simplified.mean_curvature,
        window,
        params,
    )?;
    Ok(PointCloudEvaluation {
        cd: chamfer_distance(&a, &b)?.symmetric_mean(),
        nc: normal_consistency(
            &a,
            &fa.normals,
            &b,
            &fb.normals,
            NormalOrientation::Unoriented,
        )?,
        ce: rms_difference(
            &m.original_at_reference.mean_curvature,
            &m.simplified_at_reference.mean_curvature,
        ),
        re: rms_difference(
            &m.original_at_reference.roughness,
            &m.simplified_at_reference.roughness,
        ),
        sdm: (forward + backward) / 2.0,
        sdm_nearest: structural_distortion(
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
    use meshgnn_graph::{FpsStart, fast_farthest_point_sampling, top_curvature_sampling};
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
        assert!(e_full.sdm < 1e-12 && e_full.ce == 0.0 && e_full.re == 0.0);
        for (name, five, half) in [
            ("cd", e_five.cd, e_half.cd),
            ("ce", e_five.ce, e_half.ce),
            ("re", e_five.re, e_half.re),
            ("sdm", e_five.sdm, e_half.sdm),
        ] {
            assert!(five > half && half > 0.0, "{name}: 5% {five} vs 50% {half}");
        }
    }

    /// A smooth shape with varying curvature: the unit sphere stretched to semi-axes 1.6, 1,
    /// 0.7.
    fn ellipsoid_cloud(n: usize, seed: u64) -> Vec<[f32; 3]> {
        let sphere = icosphere(5);
        let stretched = sphere
            .vertices()
            .iter()
            .map(|p| [1.6 * p[0], p[1], 0.7 * p[2]])
            .collect();
        let mesh = sphere.with_vertices(stretched).unwrap();
        sample_surface(&mesh, n, seed).unwrap().points
    }

    fn picked(points: &[[f32; 3]], indices: &[u32]) -> Vec<[f32; 3]> {
        indices.iter().map(|&i| points[i as usize]).collect()
    }

    fn fps(points: &[[f32; 3]], m: usize) -> Vec<[f32; 3]> {
        picked(
            points,
            &fast_farthest_point_sampling(points, m, FpsStart::Index(0)).unwrap(),
        )
    }

    fn tcp(points: &[[f32; 3]], m: usize) -> Vec<[f32; 3]> {
        let k_bar = curvature_features(points, 16).unwrap().mean_curvature;
        picked(points, &top_curvature_sampling(&k_bar, m).unwrap())
    }

    /// RMS of a field, the yardstick of "close to zero".
    fn rms(field: &[f32]) -> f64 {
        rms_difference(field, &vec![0.0; field.len()])
    }

    #[test]
    fn uniform_random_subsamples_score_ce_and_re_near_zero_at_any_ratio() {
        let dense = ellipsoid_cloud(40_000, 1);
        for fraction in [0.2, 0.05, 0.02] {
            let random = subset(&dense, fraction, 2);
            let e = point_cloud_evaluation(&dense, &random, 16).unwrap();
            let norm = unit_sphere_normalization(&dense).unwrap();
            let m = matched_scale_curvature(&norm.apply(&dense), &norm.apply(&random), 16, 1.0)
                .unwrap();
            // Measured 7-10% (CE) and 13-15% (RE) of the curvature signal at every ratio: the
            // sampling noise of a 16-point kernel, not a bias (docs/losses.md). Roughness of a
            // smooth surface is itself at that noise level, so both are judged against K̄.
            let k_bar = rms(&m.original_at_reference.mean_curvature);
            assert!(e.ce < 0.15 * k_bar, "{fraction}: CE {} vs K̄ {k_bar}", e.ce);
            assert!(e.re < 0.2 * k_bar, "{fraction}: RE {} vs K̄ {k_bar}", e.re);
            // the earlier own-density fields read the subsample's curvature several times over
            let own = curvature_features(&random, 16).unwrap().mean_curvature;
            let full = curvature_features(&dense, 16).unwrap().mean_curvature;
            assert!(rms(&own) > 2.0 * rms(&full), "{fraction}");
        }
    }

    #[test]
    fn tcp_scores_worse_than_fps_and_random_on_a_smooth_shape() {
        let dense = ellipsoid_cloud(40_000, 3);
        for m in [4_000, 1_000] {
            let f = point_cloud_evaluation(&dense, &fps(&dense, m), 16).unwrap();
            let r = point_cloud_evaluation(&dense, &subset(&dense, m as f64 / 4e4, 4), 16).unwrap();
            let t = point_cloud_evaluation(&dense, &tcp(&dense, m), 16).unwrap();
            for (name, tcp, fps, random) in [
                ("sdm", t.sdm, f.sdm, r.sdm),
                ("ce", t.ce, f.ce, r.ce),
                ("re", t.re, f.re, r.re),
            ] {
                assert!(
                    tcp > 2.0 * fps.max(random),
                    "{m} {name}: tcp {tcp} fps {fps} random {random}"
                );
            }
        }
    }

    #[test]
    fn values_do_not_drift_with_the_input_density() {
        // The same surface sampled 10× more densely, the same number of points kept. (At 500
        // kept points the metrics vary by ±25% between samplings of one density: the noise of
        // the simplified cloud's 16-point kernels; docs/losses.md.)
        let (sparse, dense) = (ellipsoid_cloud(20_000, 5), ellipsoid_cloud(200_000, 6));
        for m in [2_000, 1_000] {
            let a = point_cloud_evaluation(&sparse, &fps(&sparse, m), 16).unwrap();
            let b = point_cloud_evaluation(&dense, &fps(&dense, m), 16).unwrap();
            for (name, x, y) in [
                ("ce", a.ce, b.ce),
                ("re", a.re, b.re),
                ("sdm", a.sdm, b.sdm),
            ] {
                assert!(
                    (y / x - 1.0).abs() < 0.25,
                    "{m} {name}: 20k {x} vs 200k {y}"
                );
            }
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
