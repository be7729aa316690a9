//! Writing decoded shapes as a folder of OBJ files plus a PNG contact sheet, the output of
//! `handy sample` and `handy interpolate`.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use meshgnn_data::{View, contact_sheet, write_png};
use meshgnn_geometry::{OutputGuard, TriMesh, write_mesh};

/// What [`write_shape_folder`] wrote.
pub struct ShapeFolder {
    /// The meshes, in input order.
    pub meshes: Vec<TriMesh>,
    /// Their OBJ files, in input order.
    pub files: Vec<String>,
    /// The contact sheet.
    pub sheet: PathBuf,
}

/// Writes each shape (vertices on the template's faces) as `{prefix}_{i:03}.obj` in `output`
/// (created) and all of them as the contact sheet `sheet` (a PNG path) with `columns`
/// columns. The folder and every file are checked against `guard` before anything is
/// created.
pub fn write_shape_folder(
    guard: &OutputGuard,
    output: &Path,
    prefix: &str,
    sheet: PathBuf,
    columns: u32,
    template: &TriMesh,
    shapes: Vec<Vec<[f32; 3]>>,
) -> Result<ShapeFolder> {
    let paths: Vec<PathBuf> = (0..shapes.len())
        .map(|i| output.join(format!("{prefix}_{i:03}.obj")))
        .collect();
    for path in std::iter::once(output).chain(paths.iter().map(PathBuf::as_path)) {
        guard.check(path)?;
    }
    guard.check(&sheet)?;
    std::fs::create_dir_all(output).with_context(|| format!("creating {}", output.display()))?;
    let triangles = template.triangles().to_vec();
    let meshes = shapes
        .into_iter()
        .map(|v| TriMesh::new(v, triangles.clone()))
        .collect::<meshgnn_geometry::Result<Vec<_>>>()?;
    let mut files = Vec::with_capacity(meshes.len());
    for (path, mesh) in paths.iter().zip(&meshes) {
        write_mesh(path, mesh).with_context(|| format!("writing {}", path.display()))?;
        files.push(path.display().to_string());
    }
    let view = View {
        yaw: 0.0,
        pitch: -35.0,
        wireframe: false,
    };
    write_png(&sheet, &contact_sheet(&meshes, columns, 256, view)?)?;
    Ok(ShapeFolder {
        meshes,
        files,
        sheet,
    })
}
