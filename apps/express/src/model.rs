//! The model an `express` command runs: a file given with `--weights`, or the bundled one.

use std::path::Path;

use anyhow::{Context, Result};
use candle_core::Device;
use meshgnn_models::expression::ExpressionModel;
use meshgnn_models::pretrained;

/// The bundled expression generator (residual decoder: blendshapes + spiral remainder).
pub const BUNDLED_GENERATOR: &str = "expression_generator";
/// The bundled blendshape baseline.
pub const BUNDLED_BLENDSHAPE: &str = "expression_blendshape";

/// The model in `weights`, or the bundled model `bundled`.
pub fn load_model(weights: Option<&Path>, bundled: &str) -> Result<ExpressionModel> {
    match weights {
        Some(path) => ExpressionModel::load(path, &Device::Cpu)
            .with_context(|| format!("loading {}", path.display())),
        None => pretrained::load(bundled).with_context(|| format!("loading the bundled {bundled}")),
    }
}
