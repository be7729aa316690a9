//! `express eval`: thesis Table 4.2 on a 4D face dataset's `test` split (subjects never
//! trained on): per-expression and total per-vertex error (mm) of the generator and of the
//! blendshape baseline, and their temporal jitter.

use std::path::PathBuf;

use anyhow::{Result, bail};
use clap::Args;
use meshgnn_data::Expression;
use meshgnn_geometry::stdout_line;
use meshgnn_models::expression::{ExpressionEvaluation, evaluate_expressions};
use serde_json::{Map, Value, json};

use crate::face_folder::read_face_folder;
use crate::model::{BUNDLED_BLENDSHAPE, BUNDLED_GENERATOR, load_model};

/// Arguments of `express eval`.
#[derive(Args, Debug)]
pub struct EvalArgs {
    /// Dataset folder (`synth faces` output) with a `test` split.
    pub data: PathBuf,
    /// The generator's weights (default: the bundled model).
    #[arg(long)]
    pub weights: Option<PathBuf>,
    /// The blendshape baseline's weights (default: the bundled baseline).
    #[arg(long)]
    pub baseline: Option<PathBuf>,
    /// Print the figures as JSON on stdout.
    #[arg(long)]
    pub json: bool,
}

fn per_expression(e: &ExpressionEvaluation) -> Value {
    let mut map = Map::new();
    for (x, v) in Expression::ALL.iter().zip(e.per_expression_mm) {
        if let Some(v) = v {
            map.insert(x.name().into(), json!(v));
        }
    }
    Value::Object(map)
}

pub fn run(args: &EvalArgs) -> Result<()> {
    let folder = read_face_folder(&args.data, "test")?;
    let generator = load_model(args.weights.as_deref(), BUNDLED_GENERATOR)?;
    let baseline = load_model(args.baseline.as_deref(), BUNDLED_BLENDSHAPE)?;
    for (name, m) in [("generator", &generator), ("baseline", &baseline)] {
        if m.template().vertex_count() != folder.template.vertex_count() {
            bail!(
                "{}: faces of {} vertices, the {name} expects {} (the template of `synth faces`); \
                 generate matching data with `synth faces`",
                args.data.display(),
                folder.template.vertex_count(),
                m.template().vertex_count()
            );
        }
    }
    let ours = evaluate_expressions(&generator, &folder.sequences)?;
    let theirs = evaluate_expressions(&baseline, &folder.sequences)?;
    if args.json {
        stdout_line!(
            "{}",
            json!({
                "per_expression_mm": per_expression(&ours),
                "total_mm": ours.total_mm,
                "blendshape_per_expression_mm": per_expression(&theirs),
                "blendshape_total_mm": theirs.total_mm,
                "jitter_mm": ours.jitter_mm,
                "blendshape_jitter_mm": theirs.jitter_mm,
                "truth_jitter_mm": ours.truth_jitter_mm,
                "test_subjects": folder.subjects,
                "test_sequences": ours.sequences,
                "test_frames": ours.frames,
            })
        );
        return Ok(());
    }
    stdout_line!(
        "Table 4.2 on {} test subjects ({} sequences, {} frames): mean per-vertex error (mm)",
        folder.subjects,
        ours.sequences,
        ours.frames
    );
    let names: Vec<&str> = Expression::ALL.iter().map(|e| e.name()).collect();
    stdout_line!("| model | {} | total | jitter |", names.join(" | "));
    stdout_line!("|---|{}---:|---:|", "---:|".repeat(6));
    for (name, e) in [("blendshape", &theirs), ("generator", &ours)] {
        let cells: Vec<String> = e
            .per_expression_mm
            .iter()
            .map(|v| v.map_or("-".into(), |v| format!("{v:.3}")))
            .collect();
        stdout_line!(
            "| {name} | {} | {:.3} | {:.4} |",
            cells.join(" | "),
            e.total_mm,
            e.jitter_mm
        );
    }
    stdout_line!("ground-truth jitter {:.4} mm", ours.truth_jitter_mm);
    Ok(())
}
