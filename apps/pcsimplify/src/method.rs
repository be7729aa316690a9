//! The simplification methods `pcsimplify` offers (`meshgnn_models::point_selection`: the
//! learned simplifier of ch. 5.3, the point sampler of ch. 6 and the ch. 5.5 baselines)
//! applied to a read input, and the weights the learned methods read.

use std::path::Path;

use anyhow::{Context, Result};
use meshgnn_models::point_selection::{self, SelectionInput, SelectionModel};

pub use meshgnn_models::point_selection::{Selection, SelectionMethod as Method, target_count};

use crate::input::Input;

/// The trained model `method` reads: `--weights FILE` or the bundled weights; none for the
/// classical methods. A learned method's tensors are then served from freed memory kept in
/// the process (`meshgnn_models::reuse_freed_memory`).
pub fn load_model(method: Method, weights: Option<&Path>) -> Result<Option<SelectionModel>> {
    let model = SelectionModel::for_method(method, weights).with_context(|| match weights {
        Some(path) => format!("loading the {} weights {}", method.name(), path.display()),
        None => format!(
            "loading the bundled {} weights (pass --weights FILE, or choose another --method)",
            method.name()
        ),
    })?;
    if model.is_some() {
        meshgnn_models::reuse_freed_memory();
    }
    Ok(model)
}

/// Runs `method` on `input` to keep exactly `count` points (`point_selection::select`).
pub fn select(
    method: Method,
    input: &Input,
    count: usize,
    seed: u64,
    model: Option<&SelectionModel>,
) -> Result<Selection> {
    let view = SelectionInput {
        points: &input.points,
        normals: input.normals.as_deref(),
        mesh: input.mesh.as_ref(),
    };
    Ok(point_selection::select(method, &view, count, seed, model)?)
}
