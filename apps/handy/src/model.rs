//! The `handy` model file: a spiral morphable model file (`meshgnn-models`) whose metadata
//! also holds the Gaussian of the training latents (for `handy sample` and as the scan-fitting
//! prior), or a PCA model file (whose whitened latents are `N(0, I)` by construction).
//! The default model is embedded in the binary.

use std::path::Path;

use anyhow::{Context, Result, bail};
use candle_core::{Device, Tensor};
use meshgnn_geometry::TriMesh;
use meshgnn_models::spiral::{SPIRAL_MODEL_FORMAT, SpiralMorphableModel};
use meshgnn_models::{LatentGaussian, MorphableModel, PCA_FORMAT, Pca};
use serde_json::{Value, json};

/// The default Handy++ model (latent 8), trained as docs/handy.md describes.
pub const DEFAULT_MODEL: &[u8] = include_bytes!("../weights/hand_autoencoder.safetensors");

/// Metadata key of the latent Gaussian (JSON `{"mean": [..], "cholesky": [..]}`).
pub const LATENT_GAUSSIAN_KEY: &str = "latent_gaussian";

/// A loaded model: the spiral autoencoder or the PCA baseline.
pub enum HandModel {
    /// Handy++.
    Spiral(Box<SpiralMorphableModel>),
    /// Handy (PCA).
    Pca(Box<Pca>),
}

impl MorphableModel for HandModel {
    fn latent_size(&self) -> usize {
        match self {
            Self::Spiral(m) => m.latent_size(),
            Self::Pca(m) => m.latent_size(),
        }
    }
    fn template(&self) -> &TriMesh {
        match self {
            Self::Spiral(m) => m.template(),
            Self::Pca(m) => m.template(),
        }
    }
    fn encode(&self, vertices: &Tensor) -> meshgnn_models::Result<Tensor> {
        match self {
            Self::Spiral(m) => m.encode(vertices),
            Self::Pca(m) => m.encode(vertices),
        }
    }
    fn decode(&self, latents: &Tensor) -> meshgnn_models::Result<Tensor> {
        match self {
            Self::Spiral(m) => m.decode(latents),
            Self::Pca(m) => m.decode(latents),
        }
    }
}

/// A model with the Gaussian its latents are sampled from.
pub struct LoadedModel {
    /// The model.
    pub model: HandModel,
    /// The Gaussian of its training latents.
    pub gaussian: LatentGaussian,
    /// Where it came from, for messages.
    pub source: String,
}

impl LoadedModel {
    /// Short name of the model kind.
    pub fn kind(&self) -> &'static str {
        match self.model {
            HandModel::Spiral(_) => "Handy++ (spiral autoencoder)",
            HandModel::Pca(_) => "Handy (PCA)",
        }
    }
}

/// The latent Gaussian as a metadata value.
pub fn gaussian_json(g: &LatentGaussian) -> String {
    json!({"mean": g.mean(), "cholesky": g.cholesky()}).to_string()
}

fn gaussian_from_json(text: &str) -> Result<LatentGaussian> {
    let v: Value = serde_json::from_str(text)?;
    let list = |key: &str| -> Result<Vec<f64>> {
        v.get(key)
            .and_then(Value::as_array)
            .with_context(|| format!("`{key}` missing"))?
            .iter()
            .map(|x| {
                x.as_f64()
                    .with_context(|| format!("`{key}` holds a non-number"))
            })
            .collect()
    };
    Ok(LatentGaussian::from_parts(
        list("mean")?,
        list("cholesky")?,
    )?)
}

/// Reads a model from file bytes; `source` names it in errors.
pub fn model_from_bytes(bytes: &[u8], source: &str) -> Result<LoadedModel> {
    let (_, header) = safetensors::SafeTensors::read_metadata(bytes)
        .map_err(|e| anyhow::anyhow!("{source}: not a safetensors model file: {e}"))?;
    let is_pca = header
        .metadata()
        .as_ref()
        .and_then(|m| m.get("format"))
        .is_some_and(|f| f == PCA_FORMAT);
    if is_pca {
        let pca = Pca::from_bytes(bytes, Path::new(source))?;
        let gaussian = LatentGaussian::standard(pca.latent_size());
        return Ok(LoadedModel {
            model: HandModel::Pca(Box::new(pca)),
            gaussian,
            source: source.to_string(),
        });
    }
    let (model, meta) = SpiralMorphableModel::from_bytes_with_metadata(bytes, &Device::Cpu)
        .with_context(|| {
            format!("{source}: neither a {PCA_FORMAT} nor a {SPIRAL_MODEL_FORMAT} model file")
        })?;
    let gaussian = match meta.get(LATENT_GAUSSIAN_KEY) {
        Some(text) => gaussian_from_json(text)
            .with_context(|| format!("{source}: bad `{LATENT_GAUSSIAN_KEY}` metadata"))?,
        None => bail!(
            "{source}: no `{LATENT_GAUSSIAN_KEY}` metadata (an unfinished training checkpoint? \
             `handy train` writes it when training ends)"
        ),
    };
    if gaussian.latent_size() != model.latent_size() {
        bail!("{source}: latent Gaussian and model disagree on the latent size");
    }
    Ok(LoadedModel {
        model: HandModel::Spiral(Box::new(model)),
        gaussian,
        source: source.to_string(),
    })
}

/// `--model FILE`, or the embedded default.
pub fn load_model(path: Option<&Path>) -> Result<LoadedModel> {
    match path {
        Some(p) => {
            let bytes = std::fs::read(p).with_context(|| format!("reading {}", p.display()))?;
            model_from_bytes(&bytes, &p.display().to_string())
        }
        None => model_from_bytes(DEFAULT_MODEL, "the built-in model"),
    }
}

/// Fails, naming `file`, when `mesh` does not share the model template's topology.
pub fn check_topology(model: &HandModel, mesh: &TriMesh, file: &Path) -> Result<()> {
    let t = model.template();
    if mesh.vertex_count() != t.vertex_count() {
        bail!(
            "{}: {} vertices, the model's template has {} (the mesh must be registered to the template)",
            file.display(),
            mesh.vertex_count(),
            t.vertex_count()
        );
    }
    if mesh.triangles() != t.triangles() {
        bail!(
            "{}: its triangles differ from the model's template (the mesh must be registered to the template)",
            file.display()
        );
    }
    Ok(())
}
