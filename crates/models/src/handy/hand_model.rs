//! A hand model file as `handy` uses it: Handy++ (a spiral morphable model checkpoint whose
//! entries also hold the Gaussian of the training latents, for sampling and as the
//! scan-fitting prior) or Handy, the PCA baseline (whose whitened latents are `N(0, I)` by
//! construction). Which one a file holds is read from its checkpoint header.

use std::path::Path;

use candle_core::{Device, Tensor};
use meshgnn_geometry::TriMesh;

use crate::checkpoint::{checkpoint_error, read_file};
use crate::handy::spiral::{SPIRAL_MODEL_NAME, SpiralMorphableModel};
use crate::{
    CheckpointHeader, Error, LatentGaussian, LoadCheckpoint, MorphableModel, PCA_MODEL_NAME, Pca,
    Result,
};

/// Checkpoint entry of the latent Gaussian (JSON `{"mean": [..], "cholesky": [..]}`,
/// [`LatentGaussian::to_json`]).
pub const LATENT_GAUSSIAN_KEY: &str = "latent_gaussian";

/// Handy++ or Handy.
#[derive(Debug)]
pub enum HandModel {
    /// Handy++, the spiral autoencoder.
    Spiral(Box<SpiralMorphableModel>),
    /// Handy, the PCA model (eq. 3.2).
    Pca(Box<Pca>),
}

impl HandModel {
    /// Short name of the model kind, for messages.
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Spiral(_) => "Handy++ (spiral autoencoder)",
            Self::Pca(_) => "Handy (PCA)",
        }
    }
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
    fn encode(&self, vertices: &Tensor) -> Result<Tensor> {
        match self {
            Self::Spiral(m) => m.encode(vertices),
            Self::Pca(m) => m.encode(vertices),
        }
    }
    fn decode(&self, latents: &Tensor) -> Result<Tensor> {
        match self {
            Self::Spiral(m) => m.decode(latents),
            Self::Pca(m) => m.decode(latents),
        }
    }
}

/// A hand model with the Gaussian its latents are sampled from.
#[derive(Debug)]
pub struct LoadedHandModel {
    /// The model.
    pub model: HandModel,
    /// The Gaussian of its training latents.
    pub gaussian: LatentGaussian,
    /// Where it came from, for messages.
    pub source: String,
}

impl LoadedHandModel {
    /// Reads a hand model from file bytes; `source` names it in errors. A spiral model must
    /// carry its latent Gaussian (`handy train` stores it when training ends).
    pub fn from_bytes(bytes: &[u8], source: &str) -> Result<Self> {
        let path = Path::new(source);
        let header = CheckpointHeader::from_bytes(bytes, path)?;
        match header.model.as_str() {
            PCA_MODEL_NAME => {
                let pca = Pca::from_bytes(bytes, path)?;
                let gaussian = LatentGaussian::standard(pca.latent_size());
                Ok(Self {
                    model: HandModel::Pca(Box::new(pca)),
                    gaussian,
                    source: source.to_string(),
                })
            }
            SPIRAL_MODEL_NAME => {
                let model = SpiralMorphableModel::from_bytes(bytes, &Device::Cpu)
                    .map_err(|e| checkpoint_error(path, e.to_string()))?;
                let text = header.entries.get(LATENT_GAUSSIAN_KEY).ok_or_else(|| {
                    checkpoint_error(
                        path,
                        format!(
                            "no `{LATENT_GAUSSIAN_KEY}` entry (an unfinished training checkpoint? \
                             `handy train` writes it when training ends)"
                        ),
                    )
                })?;
                let gaussian = LatentGaussian::from_json(text).map_err(|e| {
                    checkpoint_error(path, format!("bad `{LATENT_GAUSSIAN_KEY}` entry: {e}"))
                })?;
                if gaussian.latent_size() != model.latent_size() {
                    return Err(checkpoint_error(
                        path,
                        "latent Gaussian and model disagree on the latent size".into(),
                    ));
                }
                Ok(Self {
                    model: HandModel::Spiral(Box::new(model)),
                    gaussian,
                    source: source.to_string(),
                })
            }
            other => Err(checkpoint_error(
                path,
                format!(
                    "holds a {other} model, not a {PCA_MODEL_NAME} or {SPIRAL_MODEL_NAME} hand model"
                ),
            )),
        }
    }

    /// Reads the hand model file at `path`.
    pub fn load(path: &Path) -> Result<Self> {
        let bytes = read_file(path)?;
        Self::from_bytes(&bytes, &path.display().to_string())
    }

    /// Short name of the model kind.
    pub fn kind(&self) -> &'static str {
        self.model.kind()
    }
}

impl LoadCheckpoint for LoadedHandModel {
    fn from_checkpoint_bytes(bytes: &[u8], source: &Path) -> Result<Self> {
        Self::from_bytes(bytes, &source.display().to_string())
    }
}

/// Fails, naming `file`, when `mesh` does not share `model`'s template topology (the mesh
/// must be registered to the template).
pub fn check_registered(model: &dyn MorphableModel, mesh: &TriMesh, file: &Path) -> Result<()> {
    let t = model.template();
    let reason = if mesh.vertex_count() != t.vertex_count() {
        format!(
            "{} vertices, the model's template has {} (the mesh must be registered to the template)",
            mesh.vertex_count(),
            t.vertex_count()
        )
    } else if mesh.triangles() != t.triangles() {
        "its triangles differ from the model's template (the mesh must be registered to the template)"
            .to_string()
    } else {
        return Ok(());
    };
    Err(Error::Invalid {
        what: file.display().to_string(),
        reason,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::handy::spiral::VertexNormalization;
    use crate::handy::spiral::test_fixtures::{deformed_shapes, tiny_config, varied_shapes};

    fn spiral_bytes(with_gaussian: bool) -> Vec<u8> {
        let sphere = meshgnn_geometry::icosphere(2);
        let shapes = deformed_shapes(&sphere, 3);
        let norm = VertexNormalization::fit(&shapes, &Device::Cpu).unwrap();
        let model =
            SpiralMorphableModel::new(&sphere, &tiny_config(8), norm, None, 0, &Device::Cpu)
                .unwrap();
        let mut c = model.to_checkpoint().unwrap();
        if with_gaussian {
            c.header.entries.insert(
                LATENT_GAUSSIAN_KEY.into(),
                LatentGaussian::standard(8).to_json(),
            );
        }
        c.to_bytes().unwrap()
    }

    #[test]
    fn reads_spiral_and_pca_files_by_their_header() {
        let spiral = LoadedHandModel::from_bytes(&spiral_bytes(true), "s.safetensors").unwrap();
        assert_eq!(spiral.kind(), "Handy++ (spiral autoencoder)");
        assert_eq!(spiral.gaussian, LatentGaussian::standard(8));
        let sphere = meshgnn_geometry::icosphere(2);
        let pca = Pca::fit(&sphere, &varied_shapes(&sphere, 4), 2).unwrap();
        let loaded = LoadedHandModel::from_bytes(&pca.to_bytes().unwrap(), "p").unwrap();
        assert_eq!(
            (loaded.kind(), loaded.model.latent_size()),
            ("Handy (PCA)", 2)
        );
        assert_eq!(loaded.gaussian, LatentGaussian::standard(2));
    }

    #[test]
    fn refuses_a_spiral_file_without_its_gaussian_and_other_files() {
        let err = LoadedHandModel::from_bytes(&spiral_bytes(false), "ckpt.st").unwrap_err();
        assert!(
            err.to_string().contains("ckpt.st") && err.to_string().contains(LATENT_GAUSSIAN_KEY),
            "{err}"
        );
        let err = LoadedHandModel::from_bytes(b"not a model", "junk.bin").unwrap_err();
        assert!(err.to_string().contains("junk.bin"), "{err}");
        let simplifier =
            crate::pretrained::bytes(crate::point_simplifier::POINT_SIMPLIFIER_NAME).unwrap();
        let err = LoadedHandModel::from_bytes(simplifier, "ps").unwrap_err();
        assert!(err.to_string().contains("point_simplifier model"), "{err}");
    }

    #[test]
    fn registration_is_checked_against_the_template() {
        let sphere = meshgnn_geometry::icosphere(2);
        let pca = Pca::fit(&sphere, &varied_shapes(&sphere, 4), 2).unwrap();
        assert!(check_registered(&pca, &sphere, Path::new("a.ply")).is_ok());
        let other = meshgnn_geometry::icosphere(1);
        let err = check_registered(&pca, &other, Path::new("b.ply")).unwrap_err();
        assert!(err.to_string().starts_with("b.ply: 42 vertices"), "{err}");
        let flipped: Vec<[u32; 3]> = sphere
            .triangles()
            .iter()
            .map(|t| [t[0], t[2], t[1]])
            .collect();
        let flipped = TriMesh::new(sphere.vertices().to_vec(), flipped).unwrap();
        let err = check_registered(&pca, &flipped, Path::new("c.ply")).unwrap_err();
        assert!(err.to_string().contains("triangles differ"), "{err}");
    }
}
