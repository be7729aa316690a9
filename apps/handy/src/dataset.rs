//! Registered-mesh datasets (`synth hands` folders or any `dataset.json` folder dataset).

use std::path::Path;

use anyhow::{Context, Result, bail};
use meshgnn_data::{FolderDataset, HandTemplate};
use meshgnn_geometry::TriMesh;
use meshgnn_models::{HandModel, MorphableModel, check_registered};
use rayon::prelude::*;

/// An opened registered dataset.
pub struct Registered {
    /// The dataset.
    pub dataset: FolderDataset,
    /// Its template (shared topology).
    pub template: TriMesh,
}

/// Opens `dir` and requires a template (registered meshes).
pub fn open(dir: &Path) -> Result<Registered> {
    let dataset =
        FolderDataset::open(dir).with_context(|| format!("opening dataset {}", dir.display()))?;
    let template = dataset.template().cloned().with_context(|| {
        format!(
            "{}: the manifest names no template; handy needs registered meshes",
            dir.display()
        )
    })?;
    Ok(Registered { dataset, template })
}

impl Registered {
    /// Refuses a folder registered to another template than `model`'s, saying which template
    /// the model expects and, when it is a `synth hands` one, the command that writes hands
    /// on it.
    fn check_template(&self, model: &HandModel) -> Result<()> {
        let expected = model.template();
        if expected.triangles() == self.template.triangles() {
            return Ok(());
        }
        let v = expected.vertex_count();
        let hint = (1..=3)
            .find(|&s| HandTemplate::new(s).is_ok_and(|t| t.vertex_count() == v))
            .map_or_else(
                || "train a model on this folder with `handy train`".to_string(),
                |s| format!("generate hands on it with `synth hands --subdivisions {s} -o DIR`"),
            );
        bail!(
            "{}: its template has {} vertices, but the model expects hands registered to its own              template of {v} vertices: {hint}",
            self.dataset.root().display(),
            self.template.vertex_count()
        )
    }

    /// True when the manifest has `split` and it lists at least one mesh.
    pub fn has_split(&self, split: &str) -> bool {
        self.dataset
            .manifest()
            .splits
            .get(split)
            .is_some_and(|names| !names.is_empty())
    }

    /// The vertices of every mesh of `split` (`#S × (#V×3)`), in manifest order. When `model`
    /// is given, the folder's template and each mesh must share its template's topology; the
    /// error names the folder (and how to generate matching hands) or the first file (in
    /// manifest order) that does not, or that cannot be read.
    pub fn load(&self, split: &str, model: Option<&HandModel>) -> Result<Vec<Vec<[f32; 3]>>> {
        if let Some(m) = model {
            self.check_template(m)?;
        }
        let names = self.dataset.split(split)?;
        let loaded: Vec<Result<Vec<[f32; 3]>>> = names
            .par_iter()
            .map(|name| {
                let mesh = self.dataset.load(name)?;
                if let Some(m) = model {
                    check_registered(m, &mesh, &self.dataset.root().join(name))?;
                }
                Ok(mesh.vertices().to_vec())
            })
            .collect();
        let shapes = loaded.into_iter().collect::<Result<Vec<_>>>()?;
        if shapes.is_empty() {
            bail!(
                "{}: split `{split}` is empty",
                self.dataset.root().display()
            );
        }
        Ok(shapes)
    }
}
