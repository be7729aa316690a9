//! `pcsimplify bench DIR [--ratios 0.2,0.1,0.05] [--methods fps,random,tcp] [--noise SIGMA]
//! [--seed S] [--k 16] [--serial] [--json]`: every method at every ratio on every cloud or mesh
//! of a folder, evaluated with the thesis' metrics (ch. 5.4) and printed in the layout of
//! Table 5.1 (means over files). With `--noise`, each input gets seeded Gaussian noise of
//! `σ × bounding-sphere radius` before simplification and is evaluated against its clean
//! original (ch. 5.5.7).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use meshgnn_data::gaussian_noise;
use meshgnn_geometry::{OutputGuard, atomic_write, mesh_files_in, stdout_line};
use meshgnn_losses::metrics::{
    EVALUATION_CURVATURE_NEIGHBOURS, TableColumn, comparison_table, point_cloud_evaluation,
};
use rayon::prelude::*;
use serde_json::{Value, json};

use crate::input::{Input, read_input};
use crate::method::{Method, load_model, select, target_count};
use meshgnn_models::point_selection::SelectionModel;

/// Arguments of `pcsimplify bench`.
#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    /// Folder of clouds and meshes (.ply .obj .off .gltf .glb .xyz; not recursive).
    pub dir: PathBuf,
    /// Simplification ratios N_s / N (comma separated).
    #[arg(long, value_delimiter = ',', default_values_t = [0.2, 0.1, 0.05])]
    pub ratios: Vec<f64>,
    /// Methods to compare (comma separated); `qem` is skipped on files without faces.
    #[arg(long, value_enum, value_delimiter = ',', default_values_t = Method::BENCH_DEFAULT)]
    pub methods: Vec<Method>,
    /// Gaussian noise σ added to the inputs, as a fraction of the bounding-sphere radius.
    #[arg(long, default_value_t = 0.0)]
    pub noise: f64,
    /// Weights of the neural simplifier (default: the bundled ones).
    #[arg(long)]
    pub weights: Option<PathBuf>,
    /// Seed of every random choice (noise of file i uses seed + i).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Neighbours for the curvature features of the metrics (eq. 5.1-5.3).
    #[arg(long, default_value_t = EVALUATION_CURVATURE_NEIGHBOURS)]
    pub k: usize,
    /// One file at a time (each method still uses every core): cleaner timings.
    #[arg(long)]
    pub serial: bool,
    /// Print one JSON object instead of Markdown.
    #[arg(long)]
    pub json: bool,
    /// Also write the JSON object to this file (atomically), whatever is printed.
    #[arg(long)]
    pub json_out: Option<PathBuf>,
}

/// The metrics of one method at one ratio on one file.
#[derive(Debug, Clone)]
struct Row {
    file: String,
    method: Method,
    ratio: f64,
    points: usize,
    kept: usize,
    /// In the order of [`COLUMNS`].
    metrics: [f64; 6],
    seconds: f64,
}

/// Metric names, their `--json` keys, the factor each is printed multiplied by, and its unit.
const COLUMNS: [(&str, &str, f64, &str); 6] = [
    ("CD", "cd", 1e4, "×10⁻⁴, squared unit-sphere units"),
    ("NC", "nc", 1.0, "in [0, 2]"),
    ("CE", "ce", 1e3, "×10⁻³, dimensionless"),
    ("RE", "re", 1e3, "×10⁻³, dimensionless"),
    ("SDM", "sdm", 1e4, "×10⁻⁴, in [0, 1] (PC-MSDM)"),
    (
        "SDM-nn",
        "sdm_nearest",
        1e2,
        "×10⁻², in [0, 1] (the earlier variant)",
    ),
];

/// `{key: value}` for each metric of [`COLUMNS`], into `object`.
fn insert_metrics(object: &mut Value, metrics: [f64; 6]) {
    for ((_, key, _, _), value) in COLUMNS.iter().zip(metrics) {
        object[*key] = json!(value);
    }
}

/// Lists the folder, runs every file, prints the table.
pub fn run(args: &BenchArgs) -> Result<()> {
    for &r in &args.ratios {
        if !(r.is_finite() && r > 0.0 && r <= 1.0) {
            bail!("--ratios: {r} is not in (0, 1]");
        }
    }
    if !(args.noise.is_finite() && args.noise >= 0.0) {
        bail!("--noise must be a finite σ >= 0, got {}", args.noise);
    }
    if args.methods.is_empty() {
        bail!("--methods: give at least one method");
    }
    crate::eval::check_curvature_neighbours(args.k)?;
    if let Some(path) = &args.json_out {
        OutputGuard::new(std::iter::once(&args.dir).chain(&args.weights)).check(path)?;
    }
    let files = mesh_files_in(&args.dir)?;
    if files.is_empty() {
        bail!(
            "{} holds no cloud or mesh (.ply .obj .off .gltf .glb .xyz)",
            args.dir.display()
        );
    }
    // The trained model of each method (in `args.methods` order); `--weights` is the neural one.
    let models: Vec<Option<SelectionModel>> = args
        .methods
        .iter()
        .map(|&m| load_model(m, args.weights.as_deref().filter(|_| m == Method::Neural)))
        .collect::<Result<_>>()?;
    let job = |(i, path): (usize, &PathBuf)| bench_file(args, &models, i, path);
    let per_file: Vec<(Vec<Row>, Vec<Value>)> = if args.serial {
        files.iter().enumerate().map(job).collect::<Result<_>>()?
    } else {
        files
            .par_iter()
            .enumerate()
            .map(job)
            .collect::<Result<_>>()?
    };
    let (rows, skipped): (Vec<Row>, Vec<Value>) = per_file.into_iter().fold(
        (Vec::new(), Vec::new()),
        |(mut rows, mut skipped), (r, s)| {
            rows.extend(r);
            skipped.extend(s);
            (rows, skipped)
        },
    );
    if rows.is_empty()
        && let Some(first) = skipped.first()
    {
        bail!(
            "no file in {} could be benchmarked ({} skipped; first: {} {})",
            args.dir.display(),
            skipped.len(),
            first["file"].as_str().unwrap_or_default(),
            first["reason"].as_str().unwrap_or_default()
        );
    }
    let names: Vec<String> = files.iter().map(|p| file_name(p)).collect();
    let report = to_json(args, &names, &rows, &skipped);
    if let Some(path) = &args.json_out {
        let text = serde_json::to_string_pretty(&report)?;
        atomic_write(path, text.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
    }
    if args.json {
        stdout_line!("{report}");
    } else {
        meshgnn_geometry::print_stdout(format_args!(
            "{}",
            to_markdown(args, &names, &rows, &skipped)
        ));
    }
    Ok(())
}

fn file_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string())
}

/// Every method at every ratio on file `index`.
fn bench_file(
    args: &BenchArgs,
    models: &[Option<SelectionModel>],
    index: usize,
    path: &Path,
) -> Result<(Vec<Row>, Vec<Value>)> {
    let name = file_name(path);
    // A file that cannot be read is listed with its error and the folder run goes on.
    let clean = match read_input(path) {
        Ok(clean) => clean,
        Err(e) => {
            let reason = format!("{e:#}");
            return Ok((Vec::new(), vec![json!({ "file": name, "reason": reason })]));
        }
    };
    let input: Input = if args.noise > 0.0 {
        let noisy = gaussian_noise(
            &clean.points,
            args.noise,
            args.seed.wrapping_add(index as u64),
        )?;
        clean.with_points(noisy)?
    } else {
        clean.clone()
    };
    let n = input.points.len();
    let mut rows = Vec::new();
    let mut skipped = Vec::new();
    for &ratio in &args.ratios {
        let count = target_count(n, Some(ratio), None).with_context(|| name.clone())?;
        if count < 3 {
            let reason = format!("ratio {ratio} keeps {count} points; the metrics need at least 3");
            skipped.push(json!({ "file": name, "ratio": ratio, "reason": reason }));
            continue;
        }
        for (&method, model) in args.methods.iter().zip(models) {
            if method == Method::Qem && input.mesh.is_none() {
                skipped
                    .push(json!({ "file": name, "method": method.name(), "reason": "no faces" }));
                continue;
            }
            let selection = select(method, &input, count, args.seed, model.as_ref())
                .with_context(|| format!("{name}: {} at ratio {ratio}", method.name()))?;
            let kept = selection.kept_points(&input.points);
            let e = point_cloud_evaluation(&clean.points, &kept, args.k).with_context(|| {
                format!("{name}: evaluating {} at ratio {ratio}", method.name())
            })?;
            rows.push(Row {
                file: name.clone(),
                method,
                ratio,
                points: n,
                kept: kept.len(),
                metrics: [e.cd, e.nc, e.ce, e.re, e.sdm, e.sdm_nearest],
                seconds: selection.seconds(),
            });
        }
    }
    Ok((rows, skipped))
}

/// Means over files of `(method, ratio)`: `(files, [metrics], seconds)`.
fn means(rows: &[Row], method: Method, ratio: f64) -> Option<(usize, [f64; 6], f64)> {
    let cell: Vec<&Row> = rows
        .iter()
        .filter(|r| r.method == method && r.ratio == ratio)
        .collect();
    if cell.is_empty() {
        return None;
    }
    let count = cell.len() as f64;
    let mut metrics = [0.0; 6];
    for r in &cell {
        for (m, v) in metrics.iter_mut().zip(r.metrics) {
            *m += v / count;
        }
    }
    let seconds = cell.iter().map(|r| r.seconds).sum::<f64>() / count;
    Some((cell.len(), metrics, seconds))
}

fn to_json(args: &BenchArgs, names: &[String], rows: &[Row], skipped: &[Value]) -> Value {
    let mut results = Vec::new();
    for &ratio in &args.ratios {
        for &method in &args.methods {
            if let Some((files, m, seconds)) = means(rows, method, ratio) {
                let mut result = json!({
                    "method": method.name(), "ratio": ratio, "files": files,
                    "seconds": seconds,
                });
                insert_metrics(&mut result, m);
                results.push(result);
            }
        }
    }
    let per_file: Vec<Value> = rows
        .iter()
        .map(|r| {
            let mut row = json!({
                "file": r.file, "method": r.method.name(), "ratio": r.ratio,
                "points": r.points, "kept": r.kept, "seconds": r.seconds,
            });
            insert_metrics(&mut row, r.metrics);
            row
        })
        .collect();
    json!({
        "dir": args.dir.display().to_string(),
        "files": names,
        "noise": args.noise,
        "seed": args.seed,
        "k": args.k,
        "units": {
            "cd": "squared unit-sphere units (both clouds scaled by the original's centroid and bounding-sphere radius)",
            "nc": "1 - |cos| of PCA normals, in [0, 2]",
            "ce": "dimensionless", "re": "dimensionless", "sdm": "in [0, 1]",
            "sdm_nearest": "in [0, 1]",
            "seconds": "selection time per file, mean",
            "noise": "σ as a fraction of the bounding-sphere radius",
        },
        "results": results,
        "per_file": per_file,
        "skipped": skipped,
    })
}

fn to_markdown(args: &BenchArgs, names: &[String], rows: &[Row], skipped: &[Value]) -> String {
    let mut out = format!(
        "Simplification of {} files in {} (noise σ = {} × bounding-sphere radius, seed {}, k = {}); \
         means over files, lower is better, best per column in bold.\n\
         Units: {}.\n\n",
        names.len(),
        args.dir.display(),
        args.noise,
        args.seed,
        args.k,
        COLUMNS
            .iter()
            .map(|(name, _, _, unit)| format!("{name} {unit}"))
            .collect::<Vec<_>>()
            .join("; ")
    );
    let methods: Vec<&str> = args.methods.iter().map(|m| m.name()).collect();
    let columns = COLUMNS.map(|(name, _, factor, _)| TableColumn { name, factor });
    out.push_str(&comparison_table(
        &methods,
        &args.ratios,
        &columns,
        |m, r| means(rows, args.methods[m], args.ratios[r]).map(|c| c.1.to_vec()),
    ));
    out.push_str("\nSelection time per file (seconds, mean):\n\n| method |");
    for ratio in &args.ratios {
        out.push_str(&format!(" @{ratio} |"));
    }
    out.push_str("\n|---|");
    for _ in &args.ratios {
        out.push_str("---:|");
    }
    out.push('\n');
    for &method in &args.methods {
        out.push_str(&format!("| {} |", method.name()));
        for &ratio in &args.ratios {
            match means(rows, method, ratio) {
                Some((_, _, s)) => out.push_str(&format!(" {s:.4} |")),
                None => out.push_str(" n/a |"),
            }
        }
        out.push('\n');
    }
    if !skipped.is_empty() {
        out.push_str("\nSkipped:\n");
        for s in skipped {
            let field = |key: &str| {
                s.get(key)
                    .map(|v| v.as_str().map_or_else(|| v.to_string(), str::to_owned))
            };
            let what = [
                field("file"),
                field("method"),
                field("ratio").map(|r| format!("ratio {r}")),
            ]
            .into_iter()
            .flatten()
            .collect::<Vec<_>>()
            .join(", ");
            out.push_str(&format!(
                "- {what}: {}\n",
                field("reason").unwrap_or_default()
            ));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use meshgnn_geometry::icosphere;

    #[test]
    fn noise_has_the_requested_sigma_and_is_seeded() {
        let sphere = icosphere(5); // 10242 points, bounding-sphere radius 1
        let points = sphere.vertices();
        let noisy = gaussian_noise(points, 0.01, 3).unwrap();
        let n = (points.len() * 3) as f64;
        let var: f64 = points
            .iter()
            .zip(&noisy)
            .flat_map(|(p, q)| (0..3).map(move |d| f64::from(q[d] - p[d]).powi(2)))
            .sum::<f64>()
            / n;
        assert!((var.sqrt() - 0.01).abs() < 0.0005, "σ = {}", var.sqrt());
        assert_eq!(noisy, gaussian_noise(points, 0.01, 3).unwrap());
        assert_ne!(noisy, gaussian_noise(points, 0.01, 4).unwrap());
    }
}
