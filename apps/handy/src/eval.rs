//! `handy eval`: thesis Table 3.2 and 3.5 on a registered dataset — generalisation (mean
//! per-vertex error, mm) on the `test` and `children` splits, specificity, compactness and
//! fitting to partial noisy scans, for Handy++ and a PCA of the same latent size fitted on the
//! same `train` split.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Result, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use meshgnn_geometry::{TriMesh, sample_surface};
use meshgnn_losses::metrics::{ErrorSummary, per_vertex_error};
use meshgnn_models::{
    LatentGaussian, MorphableModel, Pca, ScanFitOptions, fit_scan, generalisation_error,
    latent_gaussian, partial_scan, scan_distances, specificity_error,
};
use rayon::prelude::*;
use serde_json::{Value, json};

use crate::dataset;
use crate::model::{HandModel, load_model};

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

/// Parses `x,y,z`.
pub fn parse_direction(text: &str) -> std::result::Result<[f32; 3], String> {
    let v: Vec<f32> = text
        .split(',')
        .map(|s| s.trim().parse::<f32>().map_err(|e| format!("{s}: {e}")))
        .collect::<std::result::Result<_, _>>()?;
    match v.as_slice() {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok([*x, *y, *z]),
        _ => Err(format!("{text}: expected three numbers x,y,z")),
    }
}

fn summary(e: &ErrorSummary) -> Value {
    json!({"mean": e.mean, "std": e.std})
}

/// One fitting case: (partial noisy scan, clean complete surface samples, true vertices).
type ScanCase = (Vec<[f32; 3]>, Vec<[f32; 3]>, Vec<[f32; 3]>);

/// Table 3.5 figures of one model over the fitted scans (mm).
#[derive(Default, Clone, Copy)]
struct FitFigures {
    r2s: f64,
    s2r: f64,
    vertex: f64,
}

fn fit_all(
    model: &(dyn MorphableModel + Sync),
    prior: &LatentGaussian,
    scans: &[ScanCase],
    options: &ScanFitOptions,
    bar: &ProgressBar,
) -> Result<FitFigures> {
    // scans in parallel; each fit is deterministic and the sums run in scan order
    let per_scan = scans
        .par_iter()
        .map(|(scan, surface, truth)| {
            let fit = fit_scan(model, scan, Some(prior), options)?;
            let d = scan_distances(&fit.vertices, surface)?;
            let vertex = per_vertex_error(&fit.vertices, truth)?;
            bar.inc(1);
            Ok(FitFigures {
                r2s: d.r2s,
                s2r: d.s2r,
                vertex,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let n = per_scan.len().max(1) as f64;
    let sum = |f: fn(&FitFigures) -> f64| per_scan.iter().map(f).sum::<f64>() / n;
    Ok(FitFigures {
        r2s: sum(|f| f.r2s),
        s2r: sum(|f| f.s2r),
        vertex: sum(|f| f.vertex),
    })
}

pub fn run(args: &EvalArgs) -> Result<()> {
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
    eprintln!(
        "{} (latent {z}) from {}; PCA with {z} components fitted on {} training meshes",
        loaded.kind(),
        loaded.source,
        train.len()
    );
    let pca = HandModel::Pca(Box::new(Pca::fit(&data.template, &train, z)?));
    let compactness = match &pca {
        HandModel::Pca(p) => p.explained_variance_ratio(),
        HandModel::Spiral(_) => Vec::new(),
    };

    let ae_test = generalisation_error(ae, &test)?;
    let pca_test = generalisation_error(&pca, &test)?;
    let (ae_children, pca_children) = match &children {
        Some(c) => (
            Some(generalisation_error(ae, c)?),
            Some(generalisation_error(&pca, c)?),
        ),
        None => (None, None),
    };
    let ae_gauss = latent_gaussian(ae, &train)?;
    let ae_spec = specificity_error(ae, &train, &ae_gauss, args.samples, args.seed)?;
    let pca_spec = specificity_error(
        &pca,
        &train,
        &LatentGaussian::standard(z),
        args.samples,
        args.seed,
    )?;

    // Table 3.5: partial noisy scans of the first test hands
    let count = args.fit_scans.min(test.len());
    let mut fitting = Value::Null;
    let mut fit_rows = None;
    if count > 0 {
        let scans = test
            .iter()
            .take(count)
            .enumerate()
            .map(|(i, truth)| {
                let mesh = TriMesh::new(truth.clone(), data.template.triangles().to_vec())?;
                let seed = args.seed.wrapping_add(i as u64);
                let scan =
                    partial_scan(&mesh, args.camera, args.scan_points, args.scan_noise, seed)?;
                let surface = sample_surface(&mesh, 30_000, seed)?.points;
                Ok((scan, surface, truth.clone()))
            })
            .collect::<Result<Vec<_>>>()?;
        let options = ScanFitOptions {
            steps: args.fit_steps,
            seed: args.seed,
            view_direction: Some(args.camera),
            ..Default::default()
        };
        let bar = ProgressBar::new(2 * count as u64);
        if let Ok(style) = ProgressStyle::with_template("fitting scans {wide_bar} {pos}/{len}") {
            bar.set_style(style);
        }
        let ae_fit = fit_all(ae, &ae_gauss, &scans, &options, &bar)?;
        let pca_fit = fit_all(&pca, &LatentGaussian::standard(z), &scans, &options, &bar)?;
        bar.finish_and_clear();
        let mean_points = scans.iter().map(|s| s.0.len()).sum::<usize>() as f64 / count as f64;
        fitting = json!({
            "scans": count,
            "mean_scan_points": mean_points,
            "noise_mm": args.scan_noise,
            "camera": args.camera,
            "steps": args.fit_steps,
            "ae": {"r2s_mm": ae_fit.r2s, "s2r_mm": ae_fit.s2r, "per_vertex_mm": ae_fit.vertex},
            "pca": {"r2s_mm": pca_fit.r2s, "s2r_mm": pca_fit.s2r, "per_vertex_mm": pca_fit.vertex},
        });
        fit_rows = Some((ae_fit, pca_fit, mean_points));
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
        println!("{report}");
        return Ok(());
    }
    println!("Generalisation: mean per-vertex error (mm), mean ± std over meshes");
    println!(
        "| model | test ({}) | children ({}) |",
        test.len(),
        children.as_ref().map_or(0, Vec::len)
    );
    println!("|---|---:|---:|");
    let fmt = |e: Option<&ErrorSummary>| {
        e.map_or("-".into(), |e| format!("{:.3} ± {:.3}", e.mean, e.std))
    };
    println!(
        "| Handy (PCA, n_c = {z}) | {} | {} |",
        fmt(Some(&pca_test)),
        fmt(pca_children.as_ref())
    );
    println!(
        "| Handy++ (n_z = {z}) | {} | {} |",
        fmt(Some(&ae_test)),
        fmt(ae_children.as_ref())
    );
    println!();
    println!(
        "Specificity ({} samples, mm): PCA {:.3} ± {:.3}, Handy++ {:.3} ± {:.3}",
        args.samples, pca_spec.mean, pca_spec.std, ae_spec.mean, ae_spec.std
    );
    if let Some(c) = at(z) {
        println!(
            "Compactness: {z} PCA components explain {:.2} % of the training variance",
            100.0 * c
        );
    }
    if let Some((a, p, pts)) = fit_rows {
        println!();
        println!(
            "Fitting {count} partial scans (camera {:?}, ~{pts:.0} points, noise {} mm), mm:",
            args.camera, args.scan_noise
        );
        println!("| model | R2S | S2R | per-vertex |");
        println!("|---|---:|---:|---:|");
        println!(
            "| Handy (PCA, n_c = {z}) | {:.3} | {:.3} | {:.3} |",
            p.r2s, p.s2r, p.vertex
        );
        println!(
            "| Handy++ (n_z = {z}) | {:.3} | {:.3} | {:.3} |",
            a.r2s, a.s2r, a.vertex
        );
    }
    eprintln!("evaluated in {:.0} s", started.elapsed().as_secs_f64());
    Ok(())
}
