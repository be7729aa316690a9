//! The bundled models: every file of `crates/models/weights/`, embedded in the binary, loaded
//! by name through one entry, [`load`]. Next to each file, `<name>.manifest.json` records how
//! it was made (commands, seed, data, code version, wall time, figures) and its sha256 (a test
//! checks it).
//!
//! | name | model | loads as |
//! |---|---|---|
//! | `hand_autoencoder` | Handy++, latent 8 (docs/handy.md) | [`crate::LoadedHandModel`], [`crate::handy::spiral::SpiralMorphableModel`] |
//! | `point_simplifier` | the point simplifier of ch. 5.3 (docs/pcsimplify_model.md) | [`crate::point_simplifier::PointSimplifier`] |
//! | `expression_generator` | the ch. 4 expression generator, residual decoder: blendshapes + spiral remainder (docs/expression_model.md) | [`crate::expression::ExpressionModel`] |
//! | `expression_blendshape` | its PCA blendshape baseline (docs/expression_model.md) | [`crate::expression::ExpressionModel`] |
//! | `neural_mesh_simplifier` | the ch. 6 neural mesh simplifier (docs/mesh_simplifier_model.md) | [`crate::mesh_simplifier::NeuralMeshSimplifier`] |

use std::path::Path;

use crate::{Error, LoadCheckpoint, Result};

/// One bundled model.
struct Bundled {
    name: &'static str,
    bytes: &'static [u8],
    manifest: &'static str,
}

/// Every bundled model, by name.
const BUNDLED: [Bundled; 5] = [
    Bundled {
        name: "hand_autoencoder",
        bytes: include_bytes!("../weights/hand_autoencoder.safetensors"),
        manifest: include_str!("../weights/hand_autoencoder.manifest.json"),
    },
    Bundled {
        name: "point_simplifier",
        bytes: include_bytes!("../weights/point_simplifier.safetensors"),
        manifest: include_str!("../weights/point_simplifier.manifest.json"),
    },
    Bundled {
        name: "expression_generator",
        bytes: include_bytes!("../weights/expression_generator.safetensors"),
        manifest: include_str!("../weights/expression_generator.manifest.json"),
    },
    Bundled {
        name: "expression_blendshape",
        bytes: include_bytes!("../weights/expression_blendshape.safetensors"),
        manifest: include_str!("../weights/expression_blendshape.manifest.json"),
    },
    Bundled {
        name: "neural_mesh_simplifier",
        bytes: include_bytes!("../weights/neural_mesh_simplifier.safetensors"),
        manifest: include_str!("../weights/neural_mesh_simplifier.manifest.json"),
    },
];

/// The names of the bundled models.
pub fn names() -> impl Iterator<Item = &'static str> {
    BUNDLED.iter().map(|b| b.name)
}

fn find(name: &str) -> Result<&'static Bundled> {
    BUNDLED
        .iter()
        .find(|b| b.name == name)
        .ok_or_else(|| Error::Invalid {
            what: format!("bundled model {name:?}"),
            reason: format!(
                "does not exist; the bundled models are {}",
                names().collect::<Vec<_>>().join(", ")
            ),
        })
}

/// The file bytes of the bundled model `name`.
pub fn bytes(name: &str) -> Result<&'static [u8]> {
    Ok(find(name)?.bytes)
}

/// The manifest (JSON) of the bundled model `name`.
pub fn manifest(name: &str) -> Result<&'static str> {
    Ok(find(name)?.manifest)
}

/// The bundled model `name` as `M` (any model type that loads from a checkpoint); errors when
/// there is no such model or it is not an `M`.
///
/// ```
/// use meshgnn_models::pretrained;
/// use meshgnn_models::point_simplifier::PointSimplifier;
/// let model: PointSimplifier = pretrained::load("point_simplifier")?;
/// assert_eq!(model.config().hidden, 64);
/// assert!(pretrained::load::<PointSimplifier>("hand_autoencoder").is_err());
/// # Ok::<(), meshgnn_models::Error>(())
/// ```
pub fn load<M: LoadCheckpoint>(name: &str) -> Result<M> {
    let bundled = find(name)?;
    M::from_checkpoint_bytes(
        bundled.bytes,
        Path::new(&format!("<bundled>/{}.safetensors", bundled.name)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use sha2::{Digest, Sha256};

    use crate::{CheckpointHeader, LoadedHandModel, MorphableModel};

    #[test]
    fn every_manifest_names_its_file_and_matches_its_sha256() {
        let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("weights");
        let mut files: Vec<String> = std::fs::read_dir(&folder)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".safetensors"))
            .collect();
        files.sort();
        // every file of the folder is bundled, and every bundled model has a file
        let mut bundled: Vec<String> = names().map(|n| format!("{n}.safetensors")).collect();
        bundled.sort();
        assert_eq!(files, bundled);
        for b in &BUNDLED {
            let manifest: serde_json::Value = serde_json::from_str(b.manifest).unwrap();
            assert_eq!(manifest["name"], b.name);
            assert_eq!(manifest["file"], format!("{}.safetensors", b.name));
            let on_disk = std::fs::read(folder.join(format!("{}.safetensors", b.name))).unwrap();
            assert_eq!(
                on_disk, b.bytes,
                "{}: the embedded bytes are the file",
                b.name
            );
            let digest: String = Sha256::digest(&on_disk)
                .iter()
                .map(|x| format!("{x:02x}"))
                .collect();
            assert_eq!(manifest["sha256"], digest, "{}", b.name);
            for key in [
                "commands",
                "seed",
                "data",
                "wall_time_s",
                "figures",
                "code_version",
            ] {
                assert!(!manifest[key].is_null(), "{}: no {key:?}", b.name);
            }
            let header = CheckpointHeader::from_bytes(b.bytes, Path::new(b.name)).unwrap();
            assert_eq!(manifest["model"], header.model.as_str(), "{}", b.name);
        }
    }

    #[test]
    fn the_bundled_files_load_as_the_models_they_are() {
        let hand: LoadedHandModel = load("hand_autoencoder").unwrap();
        assert_eq!(hand.model.latent_size(), 8);
        assert_eq!(hand.model.template().vertex_count(), 2833);
        let simplifier: crate::point_simplifier::PointSimplifier =
            load("point_simplifier").unwrap();
        let centroidal_selector = crate::point_simplifier::PointSimplifierConfig {
            selector: crate::point_simplifier::SelectorSpace::Centroidal,
            ..Default::default()
        };
        assert_eq!(simplifier.config(), &centroidal_selector);
        for (name, decoder) in [
            (
                "expression_generator",
                crate::expression::DecoderKind::Residual,
            ),
            (
                "expression_blendshape",
                crate::expression::DecoderKind::Blendshape,
            ),
        ] {
            let model: crate::expression::ExpressionModel = load(name).unwrap();
            assert_eq!(model.config().decoder, decoder);
            assert_eq!(model.template().vertex_count(), 5040);
            // a smile at the apex moves the face; the neutral label leaves it nearly still
            let neutral = model.template().vertices().to_vec();
            let frames = model
                .generate(&[[0.0; 6], [1.0, 0.0, 0.0, 0.0, 0.0, 0.0]], &neutral)
                .unwrap();
            let moved = |f: &[[f32; 3]]| {
                f.iter()
                    .zip(&neutral)
                    .map(|(a, b)| (0..3).map(|k| (a[k] - b[k]).abs()).sum::<f32>())
                    .fold(0.0, f32::max)
            };
            assert!(moved(&frames[1]) > 2.0 && moved(&frames[0]) < 1.0, "{name}");
        }
        // The trained simplifier keeps faces where the untrained one keeps none.
        let simplifier: crate::mesh_simplifier::NeuralMeshSimplifier =
            load("neural_mesh_simplifier").unwrap();
        let sphere = meshgnn_geometry::icosphere(4); // 2 562 vertices
        let options = crate::mesh_simplifier::NeuralSimplifyOptions {
            fill_holes_up_to: Some(30),
            ..Default::default()
        };
        let out = simplifier.simplify(&sphere, 256, 0, &options).unwrap();
        assert!(
            out.mesh.face_count() > 400,
            "{} faces",
            out.mesh.face_count()
        );
        assert!(meshgnn_geometry::is_edge_manifold(&out.mesh));
        let err = load::<LoadedHandModel>("nothing").unwrap_err().to_string();
        assert!(err.contains("hand_autoencoder, point_simplifier"), "{err}");
    }
}
