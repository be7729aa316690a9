//! The simplification methods `pcsimplify` offers (`meshgnn_models::point_selection`: the
//! learned simplifier of ch. 5.3 and the ch. 5.5 baselines) applied to a read input, and the
//! simplifier weights the neural method uses.

use std::path::Path;

use anyhow::{Context, Result};
use meshgnn_models::point_selection::{self, SelectionInput};
use meshgnn_models::point_simplifier::{POINT_SIMPLIFIER_NAME, PointSimplifier};
use meshgnn_models::pretrained;

pub use meshgnn_models::point_selection::{Selection, SelectionMethod as Method, target_count};

use crate::input::Input;

/// The learned simplifier: `--weights FILE` or the bundled default weights.
pub fn load_model(weights: Option<&Path>) -> Result<PointSimplifier> {
    match weights {
        Some(path) => PointSimplifier::load(path)
            .with_context(|| format!("loading the simplifier weights {}", path.display())),
        None => pretrained::load(POINT_SIMPLIFIER_NAME).context(
            "loading the bundled simplifier weights (pass --weights FILE, or choose another --method)",
        ),
    }
}

/// Runs `method` on `input` to keep exactly `count` points (`point_selection::select`).
pub fn select(
    method: Method,
    input: &Input,
    count: usize,
    seed: u64,
    model: Option<&PointSimplifier>,
) -> Result<Selection> {
    let view = SelectionInput {
        points: &input.points,
        normals: input.normals.as_deref(),
        mesh: input.mesh.as_ref(),
    };
    Ok(point_selection::select(method, &view, count, seed, model)?)
}
