//! `handy eval`: thesis Table 3.2 and 3.5 on a registered dataset — generalisation (mean
//! per-vertex error, mm) on the `test` and `children` splits, specificity, compactness and
//! fitting to partial noisy scans, for Handy++ and a PCA of the same latent size fitted on the
//! same `train` split. The protocol is `meshgnn_models::handy::evaluate_hand_model`; this
//! module reads the data and prints the tables.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Result, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use meshgnn_geometry::{MAX_SURFACE_SAMPLES, check_count, stderr_line, stdout_line};
use meshgnn_losses::metrics::ErrorSummary;
use meshgnn_models::handy::{
    HandEvaluation, HandEvaluationOptions, HandSplits, evaluate_hand_model,
};
use meshgnn_models::{MAX_FIT_STEPS, MAX_SPECIFICITY_SAMPLES, MorphableModel};
use serde_json::{Value, json};

use crate::dataset;
use crate::model::load_model;

/// Arguments of `handy eval`.
#[derive(Args, Debug)]
pub struct EvalArgs {
    /// Dataset folder with `train`, `test` (and optionally `children`) splits.
    pub data: PathBuf,
    /// Model file (default: the built-in Handy++ model).
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// Random shapes per model for specificity (the thesis uses 1000).
    #[arg(long, default_value_t = 1000)]
    pub samples: usize,
    /// Test hands fitted from partial noisy scans (Table 3.5); 0 skips fitting.
    #[arg(long, default_value_t = 20)]
    pub fit_scans: usize,
    /// Adam steps per scan fit.
    #[arg(long, default_value_t = 300)]
    pub fit_steps: usize,
    /// Surface samples per scan before culling (about half face the camera).
    #[arg(long, default_value_t = 20000)]
    pub scan_points: usize,
    /// Gaussian noise of the scans (mm, per coordinate).
    #[arg(long, default_value_t = 0.5)]
    pub scan_noise: f64,
    /// Direction from the hand to the scanner, `x,y,z`.
    #[arg(long, default_value = "0,0,1", value_parser = parse_direction)]
    pub camera: [f32; 3],
    /// Seed of the samples and scans.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Print the results as JSON on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Parses a camera direction `x,y,z`: the direction from the hand to the scanner, which
/// decides which model vertices face the scanner. Its length does not matter but must not be
/// zero: `0,0,0` (a camera at the hand's centre) gives no view direction, so no vertex would
/// face it.
pub fn parse_direction(text: &str) -> std::result::Result<[f32; 3], String> {
    let v: Vec<f32> = text
        .split(',')
        .map(|s| s.trim().parse::<f32>().map_err(|e| format!("{s}: {e}")))
        .collect::<std::result::Result<_, _>>()?;
    match v.as_slice() {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => {
            let length =
                (f64::from(*x).powi(2) + f64::from(*y).powi(2) + f64::from(*z).powi(2)).sqrt();
            if length > 1e-12 {
                Ok([*x, *y, *z])
            } else {
                Err(format!(
                    "{text}: the camera is a direction from the hand towards the scanner and \
                     needs a non-zero length (e.g. 0,0,1): a zero vector gives no view direction"
                ))
            }
        }
        _ => Err(format!("{text}: expected three finite numbers x,y,z")),
    }
}

fn summary(e: &ErrorSummary) -> Value {
    json!({"mean": e.mean, "std": e.std})
}

pub fn run(args: &EvalArgs) -> Result<()> {
    check_count(
        "--samples",
        args.samples,
        1..=MAX_SPECIFICITY_SAMPLES,
        "decoded shapes for specificity",
    )?;
    check_count(
        "--fit-steps",
        args.fit_steps,
        1..=MAX_FIT_STEPS,
        "Adam steps per scan fit",
    )?;
    check_count(
        "--scan-points",
        args.scan_points,
        3..=MAX_SURFACE_SAMPLES,
        "surface samples per scan",
    )?;
    if !(args.scan_noise >= 0.0 && args.scan_noise.is_finite()) {
        bail!(
            "--scan-noise {}: must be a finite standard deviation >= 0 (mm)",
            args.scan_noise
        );
    }
    let started = Instant::now();
    let loaded = load_model(args.model.as_deref())?;
    let ae = &loaded.model;
    let z = ae.latent_size();
    let data = dataset::open(&args.data)?;
    let train = data.load("train", Some(ae))?;
    let test = data.load("test", Some(ae))?;
    let children = if data.has_split("children") {
        Some(data.load("children", Some(ae))?)
    } else {
        None
    };
    if train.len() <= z {
        bail!(
            "{}: {} training meshes cannot support a PCA of {z} components",
            args.data.display(),
            train.len()
        );
    }
    stderr_line!(
        "{} (latent {z}) from {}; PCA with {z} components fitted on {} training meshes",
        loaded.kind(),
        loaded.source,
        train.len()
    );
    let options = HandEvaluationOptions {
        specificity_samples: args.samples,
        fit_scans: args.fit_scans,
        fit_steps: args.fit_steps,
        scan_points: args.scan_points,
        scan_noise: args.scan_noise,
        camera: args.camera,
        seed: args.seed,
    };
    let count = args.fit_scans.min(test.len());
    let bar = ProgressBar::new(2 * count as u64);
    if let Ok(style) = ProgressStyle::with_template("fitting scans {wide_bar} {pos}/{len}") {
        bar.set_style(style);
    }
    let splits = HandSplits {
        template: &data.template,
        train: &train,
        test: &test,
        children: children.as_deref(),
    };
    let result = evaluate_hand_model(ae, &splits, &options, &|| bar.inc(1))?;
    bar.finish_and_clear();
    let HandEvaluation {
        test: (ae_test, pca_test),
        children: children_errors,
        specificity: (ae_spec, pca_spec),
        compactness,
        fitting: scan_fitting,
        ..
    } = result;
    let (ae_children, pca_children) = match children_errors {
        Some((a, p)) => (Some(a), Some(p)),
        None => (None, None),
    };
    let mut fitting = Value::Null;
    let mut fit_rows = None;
    if let Some(f) = scan_fitting {
        let (ae_fit, pca_fit) = (f.model, f.pca);
        fitting = json!({
            "scans": f.scans,
            "mean_scan_points": f.mean_scan_points,
            "noise_mm": args.scan_noise,
            "camera": args.camera,
            "steps": args.fit_steps,
            "ae": {"r2s_mm": ae_fit.r2s, "s2r_mm": ae_fit.s2r, "per_vertex_mm": ae_fit.vertex},
            "pca": {"r2s_mm": pca_fit.r2s, "s2r_mm": pca_fit.s2r, "per_vertex_mm": pca_fit.vertex},
        });
        fit_rows = Some((ae_fit, pca_fit, f.mean_scan_points));
    }

    let at = |k: usize| compactness.get(k.saturating_sub(1)).copied();
    let report = json!({
        "latent": z,
        "model": loaded.source,
        "ae_mm": ae_test.mean,
        "pca_mm": pca_test.mean,
        "test_meshes": test.len(),
        "train_meshes": train.len(),
        "children_meshes": children.as_ref().map(Vec::len),
        "splits": {
            "test": {"ae": summary(&ae_test), "pca": summary(&pca_test)},
            "children": match (&ae_children, &pca_children) {
                (Some(a), Some(p)) => json!({"ae": summary(a), "pca": summary(p)}),
                _ => Value::Null,
            },
        },
        "specificity": {
            "samples": args.samples,
            "ae": summary(&ae_spec),
            "pca": summary(&pca_spec),
        },
        "compactness": {
            "pca_explained_at_latent": at(z),
            "pca_cumulative": compactness.iter().take(50).collect::<Vec<_>>(),
        },
        "fitting": fitting,
        "seconds": started.elapsed().as_secs_f64(),
    });
    if args.json {
        stdout_line!("{report}");
        return Ok(());
    }
    stdout_line!("Generalisation: mean per-vertex error (mm), mean ± std over meshes");
    stdout_line!(
        "| model | test ({}) | children ({}) |",
        test.len(),
        children.as_ref().map_or(0, Vec::len)
    );
    stdout_line!("|---|---:|---:|");
    let fmt = |e: Option<&ErrorSummary>| {
        e.map_or("-".into(), |e| format!("{:.3} ± {:.3}", e.mean, e.std))
    };
    stdout_line!(
        "| Handy (PCA, n_c = {z}) | {} | {} |",
        fmt(Some(&pca_test)),
        fmt(pca_children.as_ref())
    );
    stdout_line!(
        "| Handy++ (n_z = {z}) | {} | {} |",
        fmt(Some(&ae_test)),
        fmt(ae_children.as_ref())
    );
    stdout_line!();
    stdout_line!(
        "Specificity ({} samples, mm): PCA {:.3} ± {:.3}, Handy++ {:.3} ± {:.3}",
        args.samples,
        pca_spec.mean,
        pca_spec.std,
        ae_spec.mean,
        ae_spec.std
    );
    if let Some(c) = at(z) {
        stdout_line!(
            "Compactness: {z} PCA components explain {:.2} % of the training variance",
            100.0 * c
        );
    }
    if let Some((a, p, pts)) = fit_rows {
        stdout_line!();
        stdout_line!(
            "Fitting {count} partial scans (camera {:?}, ~{pts:.0} points, noise {} mm), mm:",
            args.camera,
            args.scan_noise
        );
        stdout_line!("| model | R2S | S2R | per-vertex |");
        stdout_line!("|---|---:|---:|---:|");
        stdout_line!(
            "| Handy (PCA, n_c = {z}) | {:.3} | {:.3} | {:.3} |",
            p.r2s,
            p.s2r,
            p.vertex
        );
        stdout_line!(
            "| Handy++ (n_z = {z}) | {:.3} | {:.3} | {:.3} |",
            a.r2s,
            a.s2r,
            a.vertex
        );
    }
    stderr_line!("evaluated in {:.0} s", started.elapsed().as_secs_f64());
    Ok(())
}
