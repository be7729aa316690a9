//! The one checkpoint layout of every model of this crate: a safetensors file whose tensors are
//! the model's (plus, in a resumable training checkpoint, Adam's moments under
//! `optimizer.{m,v}.<name>`) and whose header carries one metadata entry `meshgnn`, a JSON
//! object with sorted keys (so equal checkpoints are equal bytes):
//!
//! | key | value |
//! |---|---|
//! | `format` | [`CHECKPOINT_FORMAT`] (`meshgnn-checkpoint/2`) |
//! | `model` | the model's name ([`crate::pretrained`] lists the bundled ones) |
//! | `config` | the model's config entries (a JSON object) |
//! | `training` | [`TrainingState`], absent when the file was not written by training |
//! | `entries` | further string entries of the model (e.g. the latent Gaussian of Handy++) |
//!
//! Files of the earlier layouts still load: `meshgnn.spiral_morphable_model.v1` (the same
//! `meshgnn` entry, config and training state as JSON strings, extra entries beside them),
//! `meshgnn-point-simplifier/1` and `meshgnn-pca` (flat metadata pairs). They are read into the
//! same [`CheckpointHeader`], so every loader handles one layout.

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use candle_core::{Device, Tensor};
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};

use crate::{Error, Result};

/// The `format` value of the current layout.
pub const CHECKPOINT_FORMAT: &str = "meshgnn-checkpoint/2";

/// Prefix of the optimiser-state tensors (ignored when a model is loaded for inference).
pub const OPTIMIZER_PREFIX: &str = "optimizer.";

/// The header metadata key holding the JSON object.
const METADATA_KEY: &str = "meshgnn";

/// `format` of spiral morphable model files before the common layout.
const SPIRAL_V1: &str = "meshgnn.spiral_morphable_model.v1";
/// `format` of point-simplifier checkpoints before the common layout.
const POINT_SIMPLIFIER_V1: &str = "meshgnn-point-simplifier/1";
/// `format` of PCA model files before the common layout.
const PCA_V1: &str = "meshgnn-pca";

/// Where training stood when a checkpoint was written ([`crate::training::train`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct TrainingState {
    /// Epochs completed.
    pub epochs_completed: usize,
    /// Optimiser steps taken.
    pub step: u64,
    /// Seed of the run.
    pub seed: u64,
    /// Mean training loss of the last completed epoch.
    pub loss: Option<f64>,
    /// Lowest validation figure so far, when the run validates.
    pub best_validation: Option<f64>,
    /// Epochs completed when `best_validation` was reached.
    pub best_epoch: Option<usize>,
}

/// Everything in a checkpoint but its tensors.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckpointHeader {
    /// The model's name (`"spiral_morphable_model"`, `"point_simplifier"`, `"pca"`).
    pub model: String,
    /// The model's config entries.
    pub config: Map<String, Value>,
    /// The training position, when training wrote the file.
    pub training: Option<TrainingState>,
    /// Further string entries of the model.
    pub entries: BTreeMap<String, String>,
}

impl CheckpointHeader {
    /// A header of `model` with `config`, no training state and no entries.
    pub fn new(model: &str, config: Map<String, Value>) -> Self {
        Self {
            model: model.to_string(),
            config,
            training: None,
            entries: BTreeMap::new(),
        }
    }

    /// The safetensors header metadata of this checkpoint (one sorted JSON entry).
    pub fn to_metadata(&self) -> Result<HashMap<String, String>> {
        let mut object = Map::new();
        object.insert("format".into(), CHECKPOINT_FORMAT.into());
        object.insert("model".into(), self.model.clone().into());
        object.insert("config".into(), Value::Object(self.config.clone()));
        if let Some(state) = &self.training {
            let value = serde_json::to_value(state).map_err(|e| Error::Invalid {
                what: "training state".into(),
                reason: format!("cannot serialise: {e}"),
            })?;
            object.insert("training".into(), value);
        }
        if !self.entries.is_empty() {
            let entries = self
                .entries
                .iter()
                .map(|(k, v)| (k.clone(), Value::from(v.clone())))
                .collect();
            object.insert("entries".into(), Value::Object(entries));
        }
        // serde_json's map is sorted by key: the header bytes are deterministic
        Ok(HashMap::from([(
            METADATA_KEY.to_string(),
            Value::Object(object).to_string(),
        )]))
    }

    /// Reads the header of safetensors `bytes` in the current or an earlier layout; `source`
    /// names the file in errors.
    pub fn from_bytes(bytes: &[u8], source: &Path) -> Result<Self> {
        let fail = |reason: String| checkpoint_error(source, reason);
        let (_, header) = safetensors::SafeTensors::read_metadata(bytes)
            .map_err(|e| fail(format!("not a safetensors file: {e}")))?;
        let meta = header.metadata().clone().unwrap_or_default();
        if let Some(json) = meta.get(METADATA_KEY) {
            let object: Map<String, Value> = serde_json::from_str(json)
                .map_err(|e| fail(format!("bad `{METADATA_KEY}` metadata: {e}")))?;
            return match object.get("format").and_then(Value::as_str) {
                Some(CHECKPOINT_FORMAT) => current(object, source),
                Some(SPIRAL_V1) => spiral_v1(object, source),
                other => Err(fail(format!(
                    "format {other:?}, expected {CHECKPOINT_FORMAT:?}"
                ))),
            };
        }
        match meta.get("format").map(String::as_str) {
            Some(POINT_SIMPLIFIER_V1) => point_simplifier_v1(&meta, source),
            Some(PCA_V1) => pca_v1(&meta, source),
            other => Err(fail(format!(
                "format {other:?}, expected {CHECKPOINT_FORMAT:?}: not a meshgnn model file"
            ))),
        }
    }

    /// Fails, naming `source`, unless the checkpoint holds `model`.
    pub fn expect_model(&self, model: &str, source: &Path) -> Result<()> {
        if self.model == model {
            return Ok(());
        }
        Err(checkpoint_error(
            source,
            format!("holds a {} model, not a {model} model", self.model),
        ))
    }

    /// The config entry `key` as a count; errors name `source`.
    pub fn config_count(&self, key: &str, source: &Path) -> Result<usize> {
        self.config
            .get(key)
            .and_then(Value::as_u64)
            .and_then(|v| usize::try_from(v).ok())
            .ok_or_else(|| {
                checkpoint_error(
                    source,
                    format!("config entry {key:?} is missing or not a count"),
                )
            })
    }
}

/// A decoded checkpoint: header and tensors (on the CPU).
#[derive(Clone, Debug)]
pub struct Checkpoint {
    /// Model name, config, training state and entries.
    pub header: CheckpointHeader,
    /// Every stored tensor by name (model tensors and optimiser moments).
    pub tensors: HashMap<String, Tensor>,
}

impl Checkpoint {
    /// The safetensors bytes of this checkpoint.
    ///
    /// ```
    /// use std::path::Path;
    /// use candle_core::{Device, Tensor};
    /// use meshgnn_models::{Checkpoint, CheckpointHeader};
    /// let config = serde_json::json!({"size": 2}).as_object().cloned().unwrap_or_default();
    /// let c = Checkpoint {
    ///     header: CheckpointHeader::new("toy", config),
    ///     tensors: [("w".to_string(), Tensor::new(&[1.0f32, 2.0], &Device::Cpu)?)].into(),
    /// };
    /// let back = Checkpoint::from_bytes(&c.to_bytes()?, Path::new("toy.safetensors"))?;
    /// assert_eq!(back.header, c.header);
    /// assert_eq!(back.tensors["w"].to_vec1::<f32>()?, vec![1.0, 2.0]);
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn to_bytes(&self) -> Result<Vec<u8>> {
        let mut names: Vec<&String> = self.tensors.keys().collect();
        names.sort();
        let tensors = names
            .into_iter()
            .filter_map(|name| self.tensors.get(name).map(|t| (name, t)))
            .map(|(name, t)| Ok((name.clone(), t.to_device(&Device::Cpu)?.contiguous()?)))
            .collect::<Result<Vec<_>>>()?;
        safetensors::serialize(
            tensors.iter().map(|(k, t)| (k.as_str(), t)),
            Some(self.header.to_metadata()?),
        )
        .map_err(|e| Error::Invalid {
            what: "checkpoint".into(),
            reason: format!("cannot serialise: {e}"),
        })
    }

    /// Decodes `bytes` (any layout [`CheckpointHeader::from_bytes`] reads); `source` names the
    /// file in errors.
    pub fn from_bytes(bytes: &[u8], source: &Path) -> Result<Self> {
        let header = CheckpointHeader::from_bytes(bytes, source)?;
        let tensors = candle_core::safetensors::load_buffer(bytes, &Device::Cpu)
            .map_err(|e| checkpoint_error(source, format!("cannot decode the tensors: {e}")))?;
        Ok(Self { header, tensors })
    }

    /// Writes the checkpoint to `path` atomically (temporary file, then rename).
    pub fn save(&self, path: &Path) -> Result<()> {
        let bytes = self
            .to_bytes()
            .map_err(|e| checkpoint_error(path, e.to_string()))?;
        meshgnn_geometry::atomic_write(path, &bytes)?;
        Ok(())
    }

    /// Reads the checkpoint at `path`.
    pub fn load(path: &Path) -> Result<Self> {
        let bytes = read_file(path)?;
        Self::from_bytes(&bytes, path)
    }

    /// The model's tensors: every tensor but the optimiser moments.
    pub fn model_tensors(&self) -> HashMap<String, Tensor> {
        self.tensors
            .iter()
            .filter(|(k, _)| !k.starts_with(OPTIMIZER_PREFIX))
            .map(|(k, t)| (k.clone(), t.clone()))
            .collect()
    }
}

/// A model that loads from checkpoint bytes (of any layout [`CheckpointHeader::from_bytes`]
/// reads): what [`crate::pretrained::load`] returns.
pub trait LoadCheckpoint: Sized {
    /// The model in `bytes`; `source` names the file in errors, which also say when the file
    /// holds another model.
    fn from_checkpoint_bytes(bytes: &[u8], source: &Path) -> Result<Self>;
}

/// The bytes of the file at `path`, with an error naming it.
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).map_err(|e| checkpoint_error(path, format!("cannot read: {e}")))
}

/// A checkpoint error naming `source`.
pub(crate) fn checkpoint_error(source: &Path, reason: String) -> Error {
    Error::Checkpoint {
        path: source.to_path_buf(),
        reason,
    }
}

/// `error` as a checkpoint error naming `path`, unless it already is one.
pub(crate) fn checkpoint_of(path: &Path, error: Error) -> Error {
    match error {
        Error::Checkpoint { .. } => error,
        other => checkpoint_error(path, other.to_string()),
    }
}

/// Checks that a model read from `source` to resume training was trained with the requested
/// config.
pub(crate) fn check_same_config<C: PartialEq + std::fmt::Debug>(
    source: &Path,
    config: &C,
    requested: &C,
) -> Result<()> {
    if config != requested {
        return Err(checkpoint_error(
            source,
            format!("was trained with {config:?}, not the requested {requested:?}"),
        ));
    }
    Ok(())
}

/// [`check_same_config`], and on a template with the requested faces.
pub(crate) fn check_resumable<C: PartialEq + std::fmt::Debug>(
    source: &Path,
    (config, triangles): (&C, &[[u32; 3]]),
    (requested, requested_triangles): (&C, &[[u32; 3]]),
) -> Result<()> {
    check_same_config(source, config, requested)?;
    if triangles != requested_triangles {
        return Err(checkpoint_error(
            source,
            "its template has different faces".into(),
        ));
    }
    Ok(())
}

/// The variables of `vars`, locked.
pub(crate) fn lock(
    vars: &candle_nn::VarMap,
) -> Result<std::sync::MutexGuard<'_, HashMap<String, candle_core::Var>>> {
    vars.data().lock().map_err(|_| Error::Invalid {
        what: "model variables".into(),
        reason: "lock poisoned by a panic in another thread".into(),
    })
}

/// Sets to zero every variable of `vars` whose name starts with one of `prefixes` (a layer
/// that must start silent, e.g. the learned half of a residual model).
pub(crate) fn zero_vars(vars: &candle_nn::VarMap, prefixes: &[String]) -> Result<()> {
    for (name, var) in lock(vars)?.iter() {
        if prefixes.iter().any(|p| name.starts_with(p.as_str())) {
            var.set(&var.zeros_like()?)?;
        }
    }
    Ok(())
}

/// A checkpoint of every variable of `vars` (detached, by name) under `header`.
pub(crate) fn vars_checkpoint(header: CheckpointHeader, vars: &candle_nn::VarMap) -> Checkpoint {
    let tensors = crate::sorted_vars(vars)
        .into_iter()
        .map(|(n, v)| (n, v.as_detached_tensor()))
        .collect();
    Checkpoint { header, tensors }
}

/// Sets every variable of `vars` from the tensor of the same name in `tensors`; errors name a
/// missing tensor or one whose shape or type differs from the variable's.
pub(crate) fn set_vars(vars: &candle_nn::VarMap, tensors: &HashMap<String, Tensor>) -> Result<()> {
    for (name, var) in lock(vars)?.iter() {
        let value = tensors.get(name).ok_or_else(|| Error::Invalid {
            what: format!("tensor `{name}`"),
            reason: "missing from the model file".into(),
        })?;
        if value.dims() != var.dims() || value.dtype() != var.dtype() {
            return Err(Error::Invalid {
                what: format!("tensor `{name}`"),
                reason: format!(
                    "{:?} {:?}, the config needs {:?} {:?}",
                    value.dtype(),
                    value.dims(),
                    var.dtype(),
                    var.dims()
                ),
            });
        }
        var.set(value)?;
    }
    Ok(())
}

fn current(mut object: Map<String, Value>, source: &Path) -> Result<CheckpointHeader> {
    let fail = |reason: String| checkpoint_error(source, reason);
    let model = match object.remove("model") {
        Some(Value::String(m)) => m,
        _ => return Err(fail("no `model` name in the header".into())),
    };
    let config = match object.remove("config") {
        Some(Value::Object(c)) => c,
        _ => return Err(fail("no `config` object in the header".into())),
    };
    let training = object
        .remove("training")
        .map(serde_json::from_value)
        .transpose()
        .map_err(|e| fail(format!("bad `training`: {e}")))?;
    let entries = match object.remove("entries") {
        None => BTreeMap::new(),
        Some(Value::Object(e)) => e
            .into_iter()
            .map(|(k, v)| match v {
                Value::String(s) => Ok((k, s)),
                _ => Err(fail(format!("entry {k:?} is not a string"))),
            })
            .collect::<Result<_>>()?,
        Some(_) => return Err(fail("`entries` is not an object".into())),
    };
    Ok(CheckpointHeader {
        model,
        config,
        training,
        entries,
    })
}

/// `meshgnn.spiral_morphable_model.v1`: `config` an object, `training` a JSON string of
/// `{epochs_completed, step, seed}`, every other key a string entry.
fn spiral_v1(mut object: Map<String, Value>, source: &Path) -> Result<CheckpointHeader> {
    let fail = |reason: String| checkpoint_error(source, reason);
    object.remove("format");
    let config = match object.remove("config") {
        Some(Value::Object(c)) => c,
        _ => return Err(fail("no `config` object in the header".into())),
    };
    let training = match object.remove("training") {
        Some(Value::String(s)) => {
            Some(serde_json::from_str(&s).map_err(|e| fail(format!("bad `training`: {e}")))?)
        }
        None => None,
        Some(_) => return Err(fail("`training` is not a string".into())),
    };
    let entries = object
        .into_iter()
        .map(|(k, v)| match v {
            Value::String(s) => (k, s),
            other => (k, other.to_string()),
        })
        .collect();
    Ok(CheckpointHeader {
        model: "spiral_morphable_model".into(),
        config,
        training,
        entries,
    })
}

/// The config keys of a `meshgnn-point-simplifier/1` header.
const POINT_SIMPLIFIER_V1_CONFIG: [&str; 7] = [
    "hidden",
    "mlp_layers",
    "gnn_neighbours",
    "refine_neighbours",
    "attention_dim",
    "phi_hidden",
    "gamma_hidden",
];

/// `meshgnn-point-simplifier/1`: flat pairs, the config's counts and, when written by
/// training, `epoch`, `step`, `seed`, `loss`, `best_validation`.
fn point_simplifier_v1(meta: &HashMap<String, String>, source: &Path) -> Result<CheckpointHeader> {
    let fail = |reason: String| checkpoint_error(source, reason);
    let get = |key: &str| -> Result<&String> {
        meta.get(key)
            .ok_or_else(|| fail(format!("metadata key {key:?} is missing")))
    };
    let config = POINT_SIMPLIFIER_V1_CONFIG
        .iter()
        .map(|&key| {
            let v: u64 = get(key)?
                .parse()
                .map_err(|e| fail(format!("metadata {key:?} is not a count: {e}")))?;
            Ok((key.to_string(), Value::from(v)))
        })
        .collect::<Result<Map<_, _>>>()?;
    let training = if meta.contains_key("epoch") {
        let number = |key: &str| -> Result<u64> {
            get(key)?
                .parse()
                .map_err(|e| fail(format!("metadata {key:?}: {e}")))
        };
        let real = |key: &str| -> Result<Option<f64>> {
            meta.get(key)
                .map(|v| v.parse::<f64>())
                .transpose()
                .map(|v| v.filter(|x| x.is_finite()))
                .map_err(|e| fail(format!("metadata {key:?}: {e}")))
        };
        let epochs_completed = usize::try_from(number("epoch")?)
            .map_err(|e| fail(format!("metadata \"epoch\": {e}")))?;
        let best_validation = real("best_validation")?;
        Some(TrainingState {
            epochs_completed,
            step: number("step")?,
            seed: number("seed")?,
            loss: real("loss")?,
            best_validation,
            best_epoch: None,
        })
    } else {
        None
    };
    Ok(CheckpointHeader {
        model: "point_simplifier".into(),
        config,
        training,
        entries: BTreeMap::new(),
    })
}

/// `meshgnn-pca`: the latent size under `latent`.
fn pca_v1(meta: &HashMap<String, String>, source: &Path) -> Result<CheckpointHeader> {
    let latent: u64 = meta
        .get("latent")
        .and_then(|v| v.parse().ok())
        .ok_or_else(|| checkpoint_error(source, "metadata \"latent\" is missing".into()))?;
    let config = Map::from_iter([("latent".to_string(), Value::from(latent))]);
    Ok(CheckpointHeader::new("pca", config))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header() -> CheckpointHeader {
        let mut h = CheckpointHeader::new(
            "toy",
            Map::from_iter([("size".to_string(), Value::from(3))]),
        );
        h.training = Some(TrainingState {
            epochs_completed: 2,
            step: 8,
            seed: 5,
            loss: Some(0.25),
            best_validation: Some(0.5),
            best_epoch: Some(1),
        });
        h.entries.insert("note".into(), "kept".into());
        h
    }

    fn with_metadata(meta: HashMap<String, String>) -> Vec<u8> {
        let t = Tensor::new(&[1.0f32], &Device::Cpu).unwrap();
        safetensors::serialize([("w", &t)], Some(meta)).unwrap()
    }

    #[test]
    fn round_trip_is_exact_and_the_bytes_deterministic() {
        let c = Checkpoint {
            header: header(),
            tensors: [
                (
                    "b".to_string(),
                    Tensor::new(&[2.0f32], &Device::Cpu).unwrap(),
                ),
                (
                    "a".to_string(),
                    Tensor::new(&[1.0f32], &Device::Cpu).unwrap(),
                ),
            ]
            .into(),
        };
        let bytes = c.to_bytes().unwrap();
        assert_eq!(bytes, c.clone().to_bytes().unwrap());
        let back = Checkpoint::from_bytes(&bytes, Path::new("x")).unwrap();
        assert_eq!(back.header, c.header);
        assert_eq!(back.tensors["b"].to_vec1::<f32>().unwrap(), vec![2.0]);
        assert!(back.header.expect_model("toy", Path::new("x")).is_ok());
        let err = back.header.expect_model("pca", Path::new("x")).unwrap_err();
        assert!(err.to_string().contains("holds a toy model"), "{err}");
        assert_eq!(back.header.config_count("size", Path::new("x")).unwrap(), 3);
        assert!(back.header.config_count("other", Path::new("x")).is_err());
    }

    #[test]
    fn earlier_layouts_read_into_the_same_header() {
        let spiral = with_metadata(HashMap::from([(
            "meshgnn".to_string(),
            r#"{"config":{"latent_size":8},"format":"meshgnn.spiral_morphable_model.v1","latent_gaussian":"{}","training":"{\"epochs_completed\":2,\"step\":4,\"seed\":5}"}"#.to_string(),
        )]));
        let h = CheckpointHeader::from_bytes(&spiral, Path::new("s")).unwrap();
        assert_eq!(h.model, "spiral_morphable_model");
        assert_eq!(h.config["latent_size"], 8);
        let t = h.training.unwrap();
        assert_eq!(
            (t.epochs_completed, t.step, t.seed, t.loss),
            (2, 4, 5, None)
        );
        assert_eq!(h.entries["latent_gaussian"], "{}");

        let mut flat: HashMap<String, String> = POINT_SIMPLIFIER_V1_CONFIG
            .iter()
            .map(|k| (k.to_string(), "4".to_string()))
            .collect();
        flat.insert("format".into(), POINT_SIMPLIFIER_V1.into());
        let h = CheckpointHeader::from_bytes(&with_metadata(flat.clone()), Path::new("p")).unwrap();
        assert_eq!((h.model.as_str(), h.training), ("point_simplifier", None));
        assert_eq!(h.config_count("gamma_hidden", Path::new("p")).unwrap(), 4);
        for (k, v) in [
            ("epoch", "3"),
            ("step", "9"),
            ("seed", "1"),
            ("loss", "NaN"),
        ] {
            flat.insert(k.into(), v.into());
        }
        flat.insert("best_validation".into(), "2.5e-1".into());
        let t = CheckpointHeader::from_bytes(&with_metadata(flat.clone()), Path::new("p"))
            .unwrap()
            .training
            .unwrap();
        assert_eq!(
            (
                t.epochs_completed,
                t.step,
                t.seed,
                t.loss,
                t.best_validation
            ),
            (3, 9, 1, None, Some(0.25))
        );
        flat.remove("hidden");
        let err = CheckpointHeader::from_bytes(&with_metadata(flat), Path::new("p")).unwrap_err();
        assert!(err.to_string().contains("\"hidden\""), "{err}");

        let pca = with_metadata(HashMap::from([
            ("format".to_string(), PCA_V1.to_string()),
            ("latent".to_string(), "8".to_string()),
        ]));
        let h = CheckpointHeader::from_bytes(&pca, Path::new("c")).unwrap();
        assert_eq!(
            (h.model.as_str(), h.config["latent"].as_u64()),
            ("pca", Some(8))
        );
    }

    #[test]
    fn other_files_are_refused_with_their_name() {
        for meta in [
            HashMap::new(),
            HashMap::from([("format".to_string(), "pt".to_string())]),
            HashMap::from([("meshgnn".to_string(), "{\"format\":\"x/9\"}".to_string())]),
            HashMap::from([("meshgnn".to_string(), "not json".to_string())]),
        ] {
            let err =
                CheckpointHeader::from_bytes(&with_metadata(meta), Path::new("f.st")).unwrap_err();
            assert!(err.to_string().starts_with("checkpoint f.st:"), "{err}");
        }
        assert!(CheckpointHeader::from_bytes(b"garbage", Path::new("g")).is_err());
    }
}
