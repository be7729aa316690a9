//! [`MeshData`]: what every reader produces before validation into a `TriMesh` or `PointCloud`.

use super::format_error::format_error;
use crate::error::Result;
use crate::{PointCloud, TriMesh};
use std::path::Path;

/// Parsed but unvalidated mesh content: `vertices: #V×3`, `triangles: #F×3`, optional
/// per-vertex `normals: #V×3`, `uvs: #V×2`, `colors: #V×3` in `[0, 1]`.
#[derive(Debug, Default, Clone, PartialEq)]
pub(crate) struct MeshData {
    pub vertices: Vec<[f32; 3]>,
    pub triangles: Vec<[u32; 3]>,
    pub normals: Option<Vec<[f32; 3]>>,
    pub uvs: Option<Vec<[f32; 2]>>,
    pub colors: Option<Vec<[f32; 3]>>,
}

impl MeshData {
    /// Copies a mesh's content (for the writers, which share this representation).
    pub fn from_mesh(mesh: &TriMesh) -> Self {
        Self {
            vertices: mesh.vertices().to_vec(),
            triangles: mesh.triangles().to_vec(),
            normals: mesh.normals().map(<[_]>::to_vec),
            uvs: mesh.uvs().map(<[_]>::to_vec),
            colors: mesh.colors().map(<[_]>::to_vec),
        }
    }

    /// Copies a cloud's content, with no triangles.
    pub fn from_point_cloud(cloud: &PointCloud) -> Self {
        Self {
            vertices: cloud.points().to_vec(),
            normals: cloud.normals().map(<[_]>::to_vec),
            ..Self::default()
        }
    }

    /// Validates into a [`TriMesh`]: finite values and in-range indices, else
    /// [`crate::Error::Format`] naming `path` and the element (`vertex 12`, `triangle 3`).
    pub fn into_mesh(self, path: &Path) -> Result<TriMesh> {
        self.check(path)?;
        let mut mesh = TriMesh::new(self.vertices, self.triangles)?;
        if let Some(normals) = self.normals {
            mesh = mesh.with_normals(normals)?;
        }
        if let Some(uvs) = self.uvs {
            mesh = mesh.with_uvs(uvs)?;
        }
        if let Some(colors) = self.colors {
            mesh = mesh.with_colors(colors)?;
        }
        Ok(mesh)
    }

    /// Validates the vertices (and normals) into a [`PointCloud`], ignoring triangles.
    pub fn into_point_cloud(mut self, path: &Path) -> Result<PointCloud> {
        self.triangles.clear();
        self.uvs = None;
        self.colors = None;
        self.check(path)?;
        let cloud = PointCloud::new(self.vertices)?;
        match self.normals {
            Some(normals) => cloud.with_normals(normals),
            None => Ok(cloud),
        }
    }

    /// The checks of `TriMesh::new`, reported as format errors of the file.
    fn check(&self, path: &Path) -> Result<()> {
        check_finite(path, "vertex", "coordinate", &self.vertices)?;
        let count = self.vertices.len();
        let attribute_lengths = [
            ("normals", self.normals.as_ref().map(Vec::len)),
            ("uvs", self.uvs.as_ref().map(Vec::len)),
            ("colors", self.colors.as_ref().map(Vec::len)),
        ];
        for (name, len) in attribute_lengths {
            if let Some(len) = len.filter(|&len| len != count) {
                return Err(format_error(
                    path,
                    format!("vertex {name}"),
                    format!("{len} entries for {count} vertices"),
                ));
            }
        }
        if let Some(normals) = &self.normals {
            check_finite(path, "vertex", "normal", normals)?;
        }
        if let Some(uvs) = &self.uvs {
            check_finite(path, "vertex", "texture coordinate", uvs)?;
        }
        if let Some(colors) = &self.colors {
            check_finite(path, "vertex", "colour", colors)?;
        }
        let bad = self
            .triangles
            .iter()
            .position(|t| t.iter().any(|&v| v as usize >= count));
        if let Some(index) = bad {
            return Err(format_error(
                path,
                format!("triangle {index}"),
                format!("vertex index out of range (there are {count} vertices)"),
            ));
        }
        Ok(())
    }
}

/// Fails at the first non-finite entry, naming `element index`.
fn check_finite<const N: usize>(
    path: &Path,
    element: &str,
    what: &str,
    values: &[[f32; N]],
) -> Result<()> {
    match crate::vec3::first_non_finite(values) {
        Some(index) => Err(format_error(
            path,
            format!("{element} {index}"),
            format!("non-finite {what}"),
        )),
        None => Ok(()),
    }
}
