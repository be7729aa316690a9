//! Which hand model a `handy` subcommand uses: `--model FILE`, or the bundled Handy++
//! (`meshgnn_models::pretrained`, "hand_autoencoder"). Reading either is the library's
//! `LoadedHandModel`.

use std::path::Path;

use anyhow::{Context, Result};
use meshgnn_models::{LoadedHandModel, pretrained};

/// The bundled model's name in `meshgnn_models::pretrained`.
const BUNDLED_MODEL: &str = "hand_autoencoder";

/// `--model FILE`, or the bundled default.
pub fn load_model(path: Option<&Path>) -> Result<LoadedHandModel> {
    match path {
        Some(p) => {
            let bytes = std::fs::read(p).with_context(|| format!("reading {}", p.display()))?;
            Ok(LoadedHandModel::from_bytes(
                &bytes,
                &p.display().to_string(),
            )?)
        }
        None => {
            let mut model: LoadedHandModel = pretrained::load(BUNDLED_MODEL)?;
            model.source = "the built-in model".into();
            Ok(model)
        }
    }
}
