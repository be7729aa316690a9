//! Registered-mesh folder datasets: a directory of meshes sharing one topology (same vertex
//! count and triangles, as registered scans are — thesis ch. 3.3, 4.4.1) described by a
//! `dataset.json` manifest, so `handy` and `express` train on user data as easily as on the
//! synthetic sets.
//!
//! Manifest schema (`dataset.json`, serde):
//! ```json
//! { "format_version": 1,
//!   "description": "synthetic hands, seed 0",
//!   "template": "template.ply",          // optional: absent for unregistered collections
//!   "splits": { "train": ["hand_00000.ply", ...], "test": [...], "children": [...] },
//!   "labels": { "hand_00000.ply": { "age": 34.2 }, ... } }
//! ```
//! `labels` is optional: free-form JSON per file (expression, frame, motion label, ...).
//! Every error names the file: a missing file, a file whose topology differs from the
//! template, a name listed twice or outside the folder, a malformed manifest. Nothing is
//! silently skipped.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use meshgnn_geometry::{TriMesh, read_mesh, write_mesh};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use meshgnn_geometry::atomic_write;

/// File name of the manifest inside a dataset folder.
pub const MANIFEST_FILE: &str = "dataset.json";

/// The `dataset.json` manifest.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// Schema version, currently 1.
    pub format_version: u32,
    /// Free text: generator, seed, units.
    #[serde(default)]
    pub description: String,
    /// The template mesh file defining the shared topology of a registered dataset; absent
    /// for collections of unrelated meshes (e.g. the simplification shapes).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub template: Option<String>,
    /// Split name → file names (relative to the folder).
    pub splits: BTreeMap<String, Vec<String>>,
    /// Optional per-file labels.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub labels: BTreeMap<String, serde_json::Value>,
}

/// A dataset folder whose manifest has been read and checked.
#[derive(Debug, Clone)]
pub struct FolderDataset {
    root: PathBuf,
    manifest: Manifest,
    template: Option<TriMesh>,
}

fn manifest_error(path: &Path, message: impl Into<String>) -> Error {
    Error::Manifest {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

/// Checks that a manifest file name is a plain name inside the folder.
fn check_name(root: &Path, name: &str) -> Result<PathBuf> {
    let bad = name.is_empty()
        || name.contains('/')
        || name.contains('\\')
        || name == "."
        || name == ".."
        || name == MANIFEST_FILE;
    if bad {
        return Err(manifest_error(
            &root.join(MANIFEST_FILE),
            format!("`{name}` is not a plain file name inside the dataset folder"),
        ));
    }
    Ok(root.join(name))
}

/// An error when `mesh` (read from `path`) does not share `template`'s topology.
fn check_topology(path: &Path, mesh: &TriMesh, template: &TriMesh) -> Result<()> {
    if mesh.vertex_count() != template.vertex_count() {
        return Err(Error::Topology {
            element: path.display().to_string(),
            message: format!(
                "{} vertices, the template has {}",
                mesh.vertex_count(),
                template.vertex_count()
            ),
        });
    }
    if mesh.triangles() != template.triangles() {
        let first = mesh
            .triangles()
            .iter()
            .zip(template.triangles())
            .position(|(a, b)| a != b)
            .unwrap_or(mesh.face_count().min(template.face_count()));
        return Err(Error::Topology {
            element: path.display().to_string(),
            message: format!(
                "triangles differ from the template (first difference at face {first}; {} vs {} faces)",
                mesh.face_count(),
                template.face_count()
            ),
        });
    }
    Ok(())
}

impl FolderDataset {
    /// Opens the dataset in `root`: parses `dataset.json`, reads the template and checks that
    /// every listed file exists (meshes are read lazily by [`FolderDataset::load`]).
    ///
    /// ```
    /// use meshgnn_data::{FolderDataset, Manifest, write_dataset};
    /// use meshgnn_geometry::icosphere;
    /// let dir = tempfile::tempdir()?;
    /// let m = icosphere(1);
    /// let manifest = Manifest {
    ///     format_version: 1, description: String::new(), template: Some("template.ply".into()),
    ///     splits: [("train".to_string(), vec!["a.ply".to_string()])].into(), labels: Default::default(),
    /// };
    /// write_dataset(dir.path(), &manifest, Some(&m), &[("a.ply".into(), m.clone())])?;
    /// let ds = FolderDataset::open(dir.path())?;
    /// assert_eq!(ds.load_split("train")?.len(), 1);
    /// std::fs::remove_file(dir.path().join("a.ply"))?;
    /// assert!(FolderDataset::open(dir.path()).unwrap_err().to_string().contains("a.ply"));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn open(root: impl AsRef<Path>) -> Result<Self> {
        let root = root.as_ref().to_path_buf();
        let path = root.join(MANIFEST_FILE);
        let text = std::fs::read_to_string(&path).map_err(|source| Error::Io {
            path: path.clone(),
            error: source,
        })?;
        let manifest: Manifest = serde_json::from_str(&text)
            .map_err(|e| manifest_error(&path, format!("invalid manifest: {e}")))?;
        if manifest.format_version != 1 {
            return Err(manifest_error(
                &path,
                format!(
                    "format_version {} is not supported (expected 1)",
                    manifest.format_version
                ),
            ));
        }
        let template = match &manifest.template {
            Some(name) => Some(read_mesh(check_name(&root, name)?)?),
            None => None,
        };
        let mut seen = BTreeMap::new();
        for (split, files) in &manifest.splits {
            for name in files {
                let file = check_name(&root, name)?;
                if let Some(other) = seen.insert(name.clone(), split.clone()) {
                    return Err(manifest_error(
                        &path,
                        format!("`{name}` is listed twice (splits `{other}` and `{split}`)"),
                    ));
                }
                if !file.is_file() {
                    return Err(manifest_error(
                        &file,
                        format!("listed in split `{split}` but missing"),
                    ));
                }
            }
        }
        for name in manifest.labels.keys() {
            if !seen.contains_key(name) {
                return Err(manifest_error(
                    &path,
                    format!("labels name `{name}`, which no split lists"),
                ));
            }
        }
        Ok(Self {
            root,
            manifest,
            template,
        })
    }

    /// The parsed manifest.
    pub fn manifest(&self) -> &Manifest {
        &self.manifest
    }

    /// The template mesh (shared topology), when the dataset is registered.
    pub fn template(&self) -> Option<&TriMesh> {
        self.template.as_ref()
    }

    /// The dataset folder.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// The file names of `split` (an error naming the split when absent).
    pub fn split(&self, split: &str) -> Result<&[String]> {
        self.manifest
            .splits
            .get(split)
            .map(Vec::as_slice)
            .ok_or_else(|| {
                manifest_error(
                    &self.root.join(MANIFEST_FILE),
                    format!(
                        "no split `{split}` (have: {})",
                        self.manifest
                            .splits
                            .keys()
                            .cloned()
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                )
            })
    }

    /// Reads file `name` and checks it shares the template's topology (when there is one).
    pub fn load(&self, name: &str) -> Result<TriMesh> {
        let path = check_name(&self.root, name)?;
        let mesh = read_mesh(&path)?;
        if let Some(template) = &self.template {
            check_topology(&path, &mesh, template)?;
        }
        Ok(mesh)
    }

    /// Reads every mesh of `split` in manifest order (in parallel).
    pub fn load_split(&self, split: &str) -> Result<Vec<TriMesh>> {
        self.split(split)?
            .par_iter()
            .map(|name| self.load(name))
            .collect()
    }
}

/// Writes `manifest` as `root/dataset.json`, atomically (pretty-printed JSON).
pub fn write_manifest(root: impl AsRef<Path>, manifest: &Manifest) -> Result<()> {
    let path = root.as_ref().join(MANIFEST_FILE);
    let text = serde_json::to_string_pretty(manifest)
        .map_err(|e| manifest_error(&path, format!("cannot serialise: {e}")))?;
    Ok(atomic_write(&path, text.as_bytes())?)
}

/// Writes a dataset folder: the template (when `manifest.template` names one), every
/// `(file name, mesh)` (format by extension, each atomically, in parallel) and the manifest
/// last, after checking that every mesh shares the template's topology and that the manifest
/// lists exactly the files given.
pub fn write_dataset(
    root: impl AsRef<Path>,
    manifest: &Manifest,
    template: Option<&TriMesh>,
    meshes: &[(String, TriMesh)],
) -> Result<()> {
    let root = root.as_ref();
    std::fs::create_dir_all(root).map_err(|source| Error::Io {
        path: root.to_path_buf(),
        error: source,
    })?;
    let listed: std::collections::BTreeSet<&String> = manifest.splits.values().flatten().collect();
    for (name, mesh) in meshes {
        let path = check_name(root, name)?;
        if let Some(template) = template {
            check_topology(&path, mesh, template)?;
        }
        if !listed.contains(name) {
            return Err(manifest_error(
                &root.join(MANIFEST_FILE),
                format!("`{name}` is written but listed in no split"),
            ));
        }
    }
    let given: std::collections::BTreeSet<&String> = meshes.iter().map(|(n, _)| n).collect();
    if let Some(missing) = listed.iter().find(|n| !given.contains(*n)) {
        return Err(manifest_error(
            &root.join(MANIFEST_FILE),
            format!("`{missing}` is listed but no mesh was given"),
        ));
    }
    match (&manifest.template, template) {
        (Some(name), Some(mesh)) => write_mesh(check_name(root, name)?, mesh)?,
        (None, None) => {}
        _ => {
            return Err(manifest_error(
                &root.join(MANIFEST_FILE),
                "the manifest names a template but none was given, or the reverse",
            ));
        }
    }
    meshes
        .par_iter()
        .map(|(name, mesh)| Ok(write_mesh(root.join(name), mesh)?))
        .collect::<Result<Vec<()>>>()?;
    write_manifest(root, manifest)
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshgnn_geometry::icosphere;

    fn manifest(files: &[&str]) -> Manifest {
        Manifest {
            format_version: 1,
            description: "test".into(),
            template: Some("template.ply".into()),
            splits: [(
                "train".to_string(),
                files.iter().map(|s| (*s).to_string()).collect(),
            )]
            .into(),
            labels: BTreeMap::new(),
        }
    }

    #[test]
    fn round_trip_and_errors_name_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let m = icosphere(1);
        let moved = m
            .clone()
            .with_vertices(
                m.vertices()
                    .iter()
                    .map(|p| [p[0] + 1.0, p[1], p[2]])
                    .collect(),
            )
            .unwrap();
        write_dataset(
            dir.path(),
            &manifest(&["a.ply", "b.obj"]),
            Some(&m),
            &[("a.ply".into(), m.clone()), ("b.obj".into(), moved.clone())],
        )
        .unwrap();
        let ds = FolderDataset::open(dir.path()).unwrap();
        let loaded = ds.load_split("train").unwrap();
        assert_eq!(loaded[1].vertices(), moved.vertices());
        assert!(ds.load_split("test").is_err());

        // A file with another topology is rejected, naming it.
        meshgnn_geometry::write_mesh(dir.path().join("b.obj"), &icosphere(2)).unwrap();
        let err = ds.load("b.obj").unwrap_err().to_string();
        assert!(err.contains("b.obj") && err.contains("vertices"), "{err}");

        // A bad manifest names the manifest.
        std::fs::write(dir.path().join(MANIFEST_FILE), "{\"format_version\": 1}").unwrap();
        let err = FolderDataset::open(dir.path()).unwrap_err().to_string();
        assert!(err.contains(MANIFEST_FILE), "{err}");
    }

    #[test]
    fn write_rejects_mismatch_and_unlisted_files() {
        let dir = tempfile::tempdir().unwrap();
        let m = icosphere(1);
        assert!(
            write_dataset(
                dir.path(),
                &manifest(&["a.ply"]),
                Some(&m),
                &[("a.ply".into(), icosphere(2))]
            )
            .is_err()
        );
        assert!(
            write_dataset(
                dir.path(),
                &manifest(&["a.ply"]),
                Some(&m),
                &[("b.ply".into(), m.clone())]
            )
            .is_err()
        );
        assert!(
            write_dataset(
                dir.path(),
                &manifest(&["../a.ply"]),
                Some(&m),
                &[("../a.ply".into(), m.clone())]
            )
            .is_err()
        );
    }
}
