//! The evaluation protocol of thesis Tables 3.2 and 3.5 on a registered dataset: Handy++
//! against a PCA of the same latent size fitted on the same `train` split — generalisation
//! (mean per-vertex error) on the `test` and `children` splits, specificity, compactness, and
//! fitting to partial noisy scans of the first test hands (ch. 3.4.4).

use meshgnn_geometry::{TriMesh, sample_surface};
use meshgnn_losses::metrics::{ErrorSummary, per_vertex_error};
use rayon::prelude::*;

use crate::{
    Error, LatentGaussian, MorphableModel, Pca, Result, ScanFitOptions, fit_scan,
    generalisation_error, latent_gaussian, partial_scan, scan_distances, specificity_error,
};

/// Clean surface samples of each true hand that the fitted scans are scored against (R2S and
/// S2R of Table 3.5): dense enough that the distance to the samples is within a few percent
/// of the distance to the surface on the 2 833-vertex hands (≈ 10 samples per vertex), and
/// the same for every model, so the two rows compare.
pub const FIT_SURFACE_SAMPLES: usize = 30_000;

/// The settings of [`evaluate_hand_model`]; defaults are `handy eval`'s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandEvaluationOptions {
    /// Random shapes per model for specificity (the thesis uses 1000).
    pub specificity_samples: usize,
    /// Test hands fitted from partial noisy scans (Table 3.5); 0 skips fitting.
    pub fit_scans: usize,
    /// Adam steps per scan fit.
    pub fit_steps: usize,
    /// Surface samples per scan before culling (about half face the camera).
    pub scan_points: usize,
    /// Gaussian noise of the scans (data units, per coordinate).
    pub scan_noise: f64,
    /// Direction from the hand to the scanner.
    pub camera: [f32; 3],
    /// Seed of the samples and scans.
    pub seed: u64,
}

impl Default for HandEvaluationOptions {
    fn default() -> Self {
        Self {
            specificity_samples: crate::SPECIFICITY_SAMPLES,
            fit_scans: 20,
            fit_steps: 300,
            scan_points: 20_000,
            scan_noise: 0.5,
            camera: [0.0, 0.0, 1.0],
            seed: 0,
        }
    }
}

/// Table 3.5 figures of one model over the fitted scans (data units).
#[derive(Debug, Default, Clone, Copy, PartialEq)]
pub struct FitFigures {
    /// Mean reconstruction-to-scan distance.
    pub r2s: f64,
    /// Mean scan-to-reconstruction distance.
    pub s2r: f64,
    /// Mean per-vertex error against the true hand.
    pub vertex: f64,
}

/// Table 3.5 of both models.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScanFitting {
    /// Scans fitted.
    pub scans: usize,
    /// Mean points per partial scan.
    pub mean_scan_points: f64,
    /// Handy++.
    pub model: FitFigures,
    /// The PCA baseline.
    pub pca: FitFigures,
}

/// Everything Tables 3.2 and 3.5 report.
#[derive(Debug, Clone, PartialEq)]
pub struct HandEvaluation {
    /// Latent size of both models.
    pub latent: usize,
    /// Generalisation on `test`: the model, the PCA.
    pub test: (ErrorSummary, ErrorSummary),
    /// Generalisation on `children`, when given.
    pub children: Option<(ErrorSummary, ErrorSummary)>,
    /// Specificity: the model (sampled from the Gaussian of its training latents), the PCA
    /// (sampled from `N(0, I)`).
    pub specificity: (ErrorSummary, ErrorSummary),
    /// Cumulative explained variance ratio of the PCA's components.
    pub compactness: Vec<f64>,
    /// Table 3.5, when `fit_scans > 0`.
    pub fitting: Option<ScanFitting>,
}

/// The registered splits of a dataset (`#S × (#V×3)` each, on `template`'s faces).
#[derive(Debug, Clone, Copy)]
pub struct HandSplits<'a> {
    /// The shared template.
    pub template: &'a TriMesh,
    /// Fits the PCA and the model's latent Gaussian.
    pub train: &'a [Vec<[f32; 3]>],
    /// Held-out adults.
    pub test: &'a [Vec<[f32; 3]>],
    /// Held-out children, when the dataset has them.
    pub children: Option<&'a [Vec<[f32; 3]>]>,
}

/// Runs the protocol for `model` on `splits`; `fitted` is called after every scan fit (for a
/// progress bar; `2 × scans` calls). Errors when `train` cannot support a PCA of the model's
/// latent size or a model rejects the data.
pub fn evaluate_hand_model(
    model: &(dyn MorphableModel + Sync),
    splits: &HandSplits<'_>,
    options: &HandEvaluationOptions,
    fitted: &(dyn Fn() + Sync),
) -> Result<HandEvaluation> {
    let z = model.latent_size();
    if splits.train.len() <= z {
        return Err(Error::Invalid {
            what: "train split".into(),
            reason: format!(
                "{} training meshes cannot support a PCA of {z} components",
                splits.train.len()
            ),
        });
    }
    let pca = Pca::fit(splits.template, splits.train, z)?;
    let test = (
        generalisation_error(model, splits.test)?,
        generalisation_error(&pca, splits.test)?,
    );
    let children = match splits.children {
        Some(c) => Some((
            generalisation_error(model, c)?,
            generalisation_error(&pca, c)?,
        )),
        None => None,
    };
    // Each model's prior: the Gaussian (and modes) of its own training codes; the PCA's
    // whitened codes have mean 0 and covariance I up to the ridge.
    let gaussian = latent_gaussian(model, splits.train)?;
    let pca_gaussian = latent_gaussian(&pca, splits.train)?;
    let (samples, seed) = (options.specificity_samples, options.seed);
    let specificity = (
        specificity_error(model, splits.train, &gaussian, samples, seed)?,
        specificity_error(&pca, splits.train, &pca_gaussian, samples, seed)?,
    );
    let count = options.fit_scans.min(splits.test.len());
    let fitting = if count > 0 {
        let scans = scan_cases(splits, count, options)?;
        let fit_options = ScanFitOptions {
            steps: options.fit_steps,
            seed,
            view_direction: Some(options.camera),
            ..Default::default()
        };
        let model_fit = fit_all(model, &gaussian, &scans, &fit_options, fitted)?;
        let pca_fit = fit_all(&pca, &pca_gaussian, &scans, &fit_options, fitted)?;
        let points = scans.iter().map(|s| s.scan.len()).sum::<usize>() as f64;
        Some(ScanFitting {
            scans: count,
            mean_scan_points: points / count as f64,
            model: model_fit,
            pca: pca_fit,
        })
    } else {
        None
    };
    Ok(HandEvaluation {
        latent: z,
        test,
        children,
        specificity,
        compactness: pca.explained_variance_ratio(),
        fitting,
    })
}

/// One fitting case.
struct ScanCase {
    /// The partial noisy scan.
    scan: Vec<[f32; 3]>,
    /// Clean samples of the complete true surface.
    surface: Vec<[f32; 3]>,
    /// The true vertices.
    truth: Vec<[f32; 3]>,
}

/// Partial noisy scans of the first `count` test hands, hand `i` seeded `seed + i`.
fn scan_cases(
    splits: &HandSplits<'_>,
    count: usize,
    options: &HandEvaluationOptions,
) -> Result<Vec<ScanCase>> {
    splits
        .test
        .iter()
        .take(count)
        .enumerate()
        .map(|(i, truth)| {
            let mesh = TriMesh::new(truth.clone(), splits.template.triangles().to_vec())?;
            let seed = options.seed.wrapping_add(i as u64);
            let scan = partial_scan(
                &mesh,
                options.camera,
                options.scan_points,
                options.scan_noise,
                seed,
            )?;
            let surface = sample_surface(&mesh, FIT_SURFACE_SAMPLES, seed)?.points;
            Ok(ScanCase {
                scan,
                surface,
                truth: truth.clone(),
            })
        })
        .collect()
}

/// Fits every scan (in parallel; each fit is deterministic and the sums run in scan order)
/// and averages the figures.
fn fit_all(
    model: &(dyn MorphableModel + Sync),
    prior: &LatentGaussian,
    scans: &[ScanCase],
    options: &ScanFitOptions,
    fitted: &(dyn Fn() + Sync),
) -> Result<FitFigures> {
    let per_scan = scans
        .par_iter()
        .map(|case| {
            let fit = fit_scan(model, &case.scan, Some(prior), options)?;
            let d = scan_distances(&fit.vertices, &case.surface)?;
            let vertex = per_vertex_error(&fit.vertices, &case.truth)?;
            fitted();
            Ok(FitFigures {
                r2s: d.r2s,
                s2r: d.s2r,
                vertex,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let n = per_scan.len().max(1) as f64;
    let mean = |f: fn(&FitFigures) -> f64| per_scan.iter().map(f).sum::<f64>() / n;
    Ok(FitFigures {
        r2s: mean(|f| f.r2s),
        s2r: mean(|f| f.s2r),
        vertex: mean(|f| f.vertex),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::handy::spiral::test_fixtures::varied_shapes as deformed_shapes;
    use std::sync::atomic::{AtomicUsize, Ordering};

    #[test]
    fn a_pca_against_itself_scores_like_the_baseline_and_fits_every_scan() {
        // the model under test is the PCA of the same split: the generalisation columns
        // must agree exactly
        let sphere = meshgnn_geometry::icosphere(2);
        let shapes = deformed_shapes(&sphere, 8);
        let (train, test) = shapes.split_at(6);
        let pca = Pca::fit(&sphere, train, 3).unwrap();
        let splits = HandSplits {
            template: &sphere,
            train,
            test,
            children: Some(&test[..1]),
        };
        let options = HandEvaluationOptions {
            specificity_samples: 5,
            fit_scans: 5,
            fit_steps: 5,
            scan_points: 400,
            ..Default::default()
        };
        let calls = AtomicUsize::new(0);
        let e = evaluate_hand_model(&pca, &splits, &options, &|| {
            calls.fetch_add(1, Ordering::Relaxed);
        })
        .unwrap();
        assert_eq!(e.latent, 3);
        assert_eq!(e.test.0, e.test.1);
        assert_eq!(e.children.unwrap().0, e.children.unwrap().1);
        let fitting = e.fitting.unwrap();
        assert_eq!(fitting.scans, 2); // only two test hands
        assert_eq!(calls.load(Ordering::Relaxed), 4);
        assert!(fitting.mean_scan_points > 0.0);
        assert_eq!(e.compactness.len(), 5); // S − 1 components
        assert!((e.compactness[4] - 1.0).abs() < 1e-9);
    }

    #[test]
    fn a_train_split_too_small_for_the_pca_is_refused() {
        let sphere = meshgnn_geometry::icosphere(2);
        let shapes = deformed_shapes(&sphere, 4);
        let pca = Pca::fit(&sphere, &shapes, 3).unwrap();
        let splits = HandSplits {
            template: &sphere,
            train: &shapes[..3],
            test: &shapes[3..],
            children: None,
        };
        let err = evaluate_hand_model(&pca, &splits, &HandEvaluationOptions::default(), &|| {})
            .unwrap_err();
        assert!(err.to_string().contains("3 training meshes"), "{err}");
    }
}
