//! The files of a folder that a folder run (`meshsimplify info DIR`, `meshsimplify simplify
//! DIR`, `pcsimplify bench DIR`) works on: regular files directly in it whose extension names a
//! supported format, sorted by name so every run visits them in the same order.

use std::path::{Path, PathBuf};

use super::MeshFormat;
use crate::error::{Error, Result};

/// The mesh and point-cloud files directly in `dir` (.obj .ply .off .gltf .glb .xyz), sorted.
/// Subfolders are not entered; other files are ignored.
///
/// ```
/// let dir = tempfile::tempdir()?;
/// std::fs::write(dir.path().join("b.obj"), "")?;
/// std::fs::write(dir.path().join("a.ply"), "")?;
/// std::fs::write(dir.path().join("notes.txt"), "")?;
/// let files = meshgnn_geometry::mesh_files_in(dir.path())?;
/// let names: Vec<_> = files.iter().map(|p| p.file_name().unwrap()).collect();
/// assert_eq!(names, ["a.ply", "b.obj"]);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn mesh_files_in(dir: &Path) -> Result<Vec<PathBuf>> {
    let io_error = |error| Error::Io {
        path: dir.to_path_buf(),
        error,
    };
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(io_error)? {
        let path = entry.map_err(io_error)?.path();
        if path.is_file() && MeshFormat::from_path(&path).is_ok() {
            files.push(path);
        }
    }
    files.sort();
    Ok(files)
}
