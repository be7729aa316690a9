//! Registered-mesh datasets (`synth hands` folders or any `dataset.json` folder dataset).

use std::path::Path;

use anyhow::{Context, Result, bail};
use meshgnn_data::FolderDataset;
use meshgnn_geometry::TriMesh;
use meshgnn_models::{HandModel, check_registered};
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
    /// True when the manifest has `split`.
    pub fn has_split(&self, split: &str) -> bool {
        self.dataset.manifest().splits.contains_key(split)
    }

    /// The vertices of every mesh of `split` (`#S × (#V×3)`), in manifest order. When `model`
    /// is given, each mesh must share its template's topology; the error names the first
    /// file (in manifest order) that does not, or that cannot be read.
    pub fn load(&self, split: &str, model: Option<&HandModel>) -> Result<Vec<Vec<[f32; 3]>>> {
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
