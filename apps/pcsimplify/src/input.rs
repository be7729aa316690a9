//! Reading a simplifier input: a mesh keeps its faces (QEM and the neural GNN use its
//! adjacency), anything else is a point cloud.

use std::path::Path;

use anyhow::{Context, Result};
use meshgnn_geometry::{PointCloud, TriMesh, check_input_points, read_mesh, read_point_cloud};

/// A cloud to simplify: `points: #P×3`, optional `normals: #P×3`, and the mesh it came from
/// when the file had faces.
#[derive(Debug, Clone)]
pub struct Input {
    /// The points (a mesh's vertices).
    pub points: Vec<[f32; 3]>,
    /// Per-point normals when the file stores them.
    pub normals: Option<Vec<[f32; 3]>>,
    /// The mesh, when the file has at least one face.
    pub mesh: Option<TriMesh>,
}

impl Input {
    /// A cloud without faces.
    pub fn from_cloud(cloud: PointCloud) -> Self {
        let (points, normals) = cloud.into_parts();
        Self {
            points,
            normals,
            mesh: None,
        }
    }

    /// A mesh: its vertices are the points.
    pub fn from_mesh(mesh: TriMesh) -> Self {
        Self {
            points: mesh.vertices().to_vec(),
            normals: mesh.normals().map(<[_]>::to_vec),
            mesh: Some(mesh),
        }
    }

    /// The same input with `points` replaced (noise experiments); the mesh keeps its faces.
    pub fn with_points(&self, points: Vec<[f32; 3]>) -> Result<Self> {
        let mesh = match &self.mesh {
            Some(mesh) => Some(mesh.clone().with_vertices(points.clone())?),
            None => None,
        };
        Ok(Self {
            points,
            normals: None,
            mesh,
        })
    }
}

/// Reads `path`: a mesh when it has faces, else its points (PLY, OBJ, OFF, glTF/GLB, XYZ).
pub fn read_input(path: &Path) -> Result<Input> {
    let input = match read_mesh(path) {
        Ok(mesh) if mesh.face_count() > 0 => Input::from_mesh(mesh),
        _ => Input::from_cloud(
            read_point_cloud(path).with_context(|| format!("reading {}", path.display()))?,
        ),
    };
    check_input_points(path, &input.points)?;
    Ok(input)
}
