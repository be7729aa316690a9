//! `meshsimplify bench DIR [--ratios 0.05,0.1,0.2,0.5] [--methods neural,qem,pc+remesh]
//! [--samples 50000] [--seed S] [--neural-weights FILE] [--keep-positions] [--fill-holes [K]]
//! [--json] [--json-out FILE]`: every method at every ratio on every mesh of a folder, scored
//! like `meshsimplify eval` and printed in the layout of thesis Table 6.1 (CD, WA, LE, NE and
//! seconds per mesh, means over files). The thesis' WA is its network's own output: `WA raw`
//! is that for the neural method, before its manifold pass, and the output's WA for the
//! others; `WA` is the output's.
//!
//! Files run one after another (each method and the eigen-solves of LE use every core), so the
//! seconds are comparable. A file that cannot be read, or a method that fails on a file, is
//! listed under "skipped" with its reason and the bench goes on.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use meshgnn_geometry::{
    InputUse, OutputGuard, atomic_write, mesh_files_in, read_input_mesh, stdout_line,
};
use meshgnn_graph::Target;
use meshgnn_losses::metrics::{
    MAX_MESH_EVALUATION_SAMPLES, MESH_EVALUATION_SAMPLES, TableColumn, comparison_table,
    mesh_evaluation,
};
use serde_json::{Value, json};

use crate::method::{Method, MethodOptions, Simplifier};

/// Arguments of `meshsimplify bench`.
#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    /// Folder of meshes (.obj .ply .off .gltf .glb; not recursive).
    pub dir: PathBuf,
    /// Simplification ratios (comma separated): faces kept by qem, vertices kept by the
    /// selecting methods.
    #[arg(long, value_delimiter = ',', default_values_t = [0.05, 0.1, 0.2, 0.5])]
    pub ratios: Vec<f64>,
    /// Methods to compare (comma separated).
    #[arg(long, value_enum, value_delimiter = ',', default_values_t = [Method::Neural, Method::Qem, Method::PcRemesh])]
    pub methods: Vec<Method>,
    /// Surface samples per mesh for CD (the thesis uses 50 000).
    #[arg(long, default_value_t = MESH_EVALUATION_SAMPLES)]
    pub samples: usize,
    /// Seed of the selecting methods and of the surface sampling.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Weights of the neural simplifier from a training run (default: the bundled ones).
    #[arg(long)]
    pub neural_weights: Option<PathBuf>,
    /// The neural method leaves its selected vertices at their input positions (the thesis'
    /// output) instead of placing them.
    #[arg(long)]
    pub keep_positions: bool,
    /// The neural method closes the holes of at most K boundary edges after its manifold
    /// pass, as `simplify --fill-holes` does.
    #[arg(long, value_name = "K", num_args = 0..=1, default_missing_value = "30")]
    pub fill_holes: Option<usize>,
    /// Print one JSON object instead of Markdown.
    #[arg(long)]
    pub json: bool,
    /// Also write the JSON object to this file (atomically), whatever is printed.
    #[arg(long)]
    pub json_out: Option<PathBuf>,
}

/// Metric names, their `--json` keys, the factor each is printed multiplied by, and its unit.
const COLUMNS: [(&str, &str, f64, &str); 6] = [
    ("CD", "cd", 1e4, "×10⁻⁴, squared unit-sphere units"),
    (
        "WA raw",
        "wa_raw",
        1.0,
        "% of edges without exactly two faces, before the neural method's manifold pass",
    ),
    ("WA", "wa", 1.0, "% of edges without exactly two faces"),
    ("LE", "le", 1.0, "eq. 6.16, dimensionless"),
    ("NE", "ne", 1.0, "eq. 6.15, in [0, 4]"),
    ("s", "seconds", 1.0, "seconds per mesh"),
];

/// One method at one ratio on one file, the metrics in the order of [`COLUMNS`].
struct Row {
    file: String,
    method: Method,
    ratio: f64,
    faces: usize,
    holes: usize,
    metrics: [f64; COLUMNS.len()],
}

/// Lists the folder, runs every file, prints the table.
pub fn run(args: &BenchArgs) -> Result<()> {
    for &r in &args.ratios {
        if !(r.is_finite() && r > 0.0 && r <= 1.0) {
            bail!("--ratios: {r} is not in (0, 1]");
        }
    }
    if args.methods.is_empty() {
        bail!("--methods: give at least one method");
    }
    if !(1..=MAX_MESH_EVALUATION_SAMPLES).contains(&args.samples) {
        bail!(
            "--samples must be in 1..={MAX_MESH_EVALUATION_SAMPLES}, got {}",
            args.samples
        );
    }
    if let Some(path) = &args.json_out {
        OutputGuard::new(std::iter::once(&args.dir).chain(&args.neural_weights)).check(path)?;
    }
    let files = mesh_files_in(&args.dir)?;
    if files.is_empty() {
        bail!(
            "{} holds no mesh (.obj .ply .off .gltf .glb)",
            args.dir.display()
        );
    }
    // One simplifier per method and ratio, weights loaded before any file is read.
    let mut simplifiers = Vec::new();
    for &method in &args.methods {
        for &ratio in &args.ratios {
            let options = MethodOptions {
                weights: args
                    .neural_weights
                    .as_deref()
                    .filter(|_| method == Method::Neural),
                keep_positions: args.keep_positions && method == Method::Neural,
                fill_holes: args.fill_holes.filter(|_| method == Method::Neural),
                seed: args.seed,
                ..Default::default()
            };
            simplifiers.push((
                method,
                ratio,
                Simplifier::new(method, Target::Ratio(ratio), &options)?,
            ));
        }
    }
    let bar = ProgressBar::new((files.len() * simplifiers.len()) as u64);
    bar.set_style(
        ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {pos}/{len} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mut rows = Vec::new();
    let mut skipped = Vec::new();
    for path in &files {
        let name = file_name(path);
        let mesh = match read_input_mesh(path, InputUse::Surface) {
            Ok(mesh) => mesh,
            Err(e) => {
                skipped.push(json!({ "file": name, "reason": format!("{e:#}") }));
                bar.inc(simplifiers.len() as u64);
                continue;
            }
        };
        for (method, ratio, simplifier) in &simplifiers {
            bar.set_message(format!("{name}: {} at {ratio}", method.name()));
            let scored = simplifier
                .run(&mesh, &mut |_| {})
                .and_then(|(simplified, outcome)| {
                    let e = mesh_evaluation(&mesh, &simplified, args.samples, args.seed)?;
                    let wa_raw = outcome.watertightness.as_ref().map_or(e.wa, |w| w.wa_raw);
                    Ok(Row {
                        file: name.clone(),
                        method: *method,
                        ratio: *ratio,
                        faces: simplified.face_count(),
                        holes: e.holes,
                        metrics: [e.cd, wa_raw, e.wa, e.le, e.ne, outcome.seconds],
                    })
                });
            match scored {
                Ok(row) => rows.push(row),
                Err(e) => skipped.push(json!({
                    "file": name, "method": method.name(), "ratio": ratio,
                    "reason": format!("{e:#}"),
                })),
            }
            bar.inc(1);
        }
    }
    bar.finish_and_clear();
    if rows.is_empty() {
        bail!(
            "nothing in {} could be benchmarked ({} skipped; first: {})",
            args.dir.display(),
            skipped.len(),
            skipped.first().map(Value::to_string).unwrap_or_default()
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

/// Means over the files of `(method, ratio)`: `(files, metrics)`.
fn means(rows: &[Row], method: Method, ratio: f64) -> Option<(usize, [f64; COLUMNS.len()])> {
    let cell: Vec<&Row> = rows
        .iter()
        .filter(|r| r.method == method && r.ratio == ratio)
        .collect();
    if cell.is_empty() {
        return None;
    }
    let mut metrics = [0.0; COLUMNS.len()];
    for r in &cell {
        for (m, v) in metrics.iter_mut().zip(r.metrics) {
            *m += v / cell.len() as f64;
        }
    }
    Some((cell.len(), metrics))
}

fn to_json(args: &BenchArgs, names: &[String], rows: &[Row], skipped: &[Value]) -> Value {
    let with_metrics = |mut object: Value, metrics: [f64; COLUMNS.len()]| {
        for ((_, key, _, _), value) in COLUMNS.iter().zip(metrics) {
            object[*key] = json!(value);
        }
        object
    };
    let mut results = Vec::new();
    for &ratio in &args.ratios {
        for &method in &args.methods {
            if let Some((files, m)) = means(rows, method, ratio) {
                let cell = json!({ "method": method.name(), "ratio": ratio, "files": files });
                results.push(with_metrics(cell, m));
            }
        }
    }
    let per_file: Vec<Value> = rows
        .iter()
        .map(|r| {
            let row = json!({
                "file": r.file, "method": r.method.name(), "ratio": r.ratio,
                "faces": r.faces, "holes": r.holes,
            });
            with_metrics(row, r.metrics)
        })
        .collect();
    json!({
        "dir": args.dir.display().to_string(),
        "files": names,
        "samples": args.samples,
        "seed": args.seed,
        "units": COLUMNS.iter().map(|(_, key, _, unit)| (key.to_string(), json!(unit))).collect::<serde_json::Map<_, _>>(),
        "results": results,
        "per_file": per_file,
        "skipped": skipped,
    })
}

fn to_markdown(args: &BenchArgs, names: &[String], rows: &[Row], skipped: &[Value]) -> String {
    let units: Vec<String> = COLUMNS
        .iter()
        .map(|(name, _, _, unit)| format!("{name} {unit}"))
        .collect();
    let mut out = format!(
        "Simplification of {} meshes in {} (seed {}, {} samples); means over files, lower is \
         better, best per column in bold.\nUnits: {}.\n\n",
        names.len(),
        args.dir.display(),
        args.seed,
        args.samples,
        units.join("; ")
    );
    let methods: Vec<&str> = args.methods.iter().map(|m| m.name()).collect();
    let columns = COLUMNS.map(|(name, _, factor, _)| TableColumn { name, factor });
    out.push_str(&comparison_table(
        &methods,
        &args.ratios,
        &columns,
        |m, r| means(rows, args.methods[m], args.ratios[r]).map(|c| c.1.to_vec()),
    ));
    if !skipped.is_empty() {
        out.push_str("\nSkipped:\n");
        for s in skipped {
            out.push_str(&format!("- {s}\n"));
        }
    }
    out
}
