//! [`TriMesh`]: an indexed triangle mesh with optional per-vertex attributes.
//!
//! # Conventions
//! - Vertices are `#V×3` `f32` positions; triangles are `#F×3` `u32` vertex indices,
//!   counter-clockwise seen from outside (the right-hand rule gives the outward normal).
//! - Optional attributes (normals `#V×3`, uvs `#V×2`, colours `#V×3` in `[0, 1]`) are per
//!   vertex; formats with per-corner attributes split vertices on seams when read.
//! - Construction validates what every algorithm relies on: indices in range and finite
//!   values. Degenerate faces (a repeated vertex index) and duplicate faces (the same three
//!   vertices twice) are *kept* so that reading and writing a file loses nothing; they are
//!   counted by [`crate::degenerate_faces`] and dropped on request by
//!   [`TriMesh::without_degenerate_faces`].

use crate::error::{Error, Result};

/// An indexed triangle mesh. Fields are private so the validation of [`TriMesh::new`] holds.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TriMesh {
    vertices: Vec<[f32; 3]>,
    triangles: Vec<[u32; 3]>,
    normals: Option<Vec<[f32; 3]>>,
    uvs: Option<Vec<[f32; 2]>>,
    colors: Option<Vec<[f32; 3]>>,
}

impl TriMesh {
    /// A mesh from `vertices: #V×3` and `triangles: #F×3`.
    ///
    /// Fails on a non-finite coordinate or a vertex index `>= #V`.
    ///
    /// ```
    /// use meshgnn_geometry::TriMesh;
    /// let mesh = TriMesh::new(vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], vec![[0, 1, 2]])?;
    /// assert_eq!((mesh.vertex_count(), mesh.face_count()), (3, 1));
    /// assert!(TriMesh::new(vec![[0.0; 3]], vec![[0, 1, 2]]).is_err());
    /// # Ok::<(), meshgnn_geometry::Error>(())
    /// ```
    pub fn new(vertices: Vec<[f32; 3]>, triangles: Vec<[u32; 3]>) -> Result<Self> {
        check_finite("vertex", &vertices)?;
        let count = vertices.len();
        for (index, triangle) in triangles.iter().enumerate() {
            if let Some(&value) = triangle.iter().find(|&&v| v as usize >= count) {
                return Err(Error::IndexOutOfRange {
                    element: "triangle",
                    index,
                    target: "vertex",
                    value: u64::from(value),
                    count,
                });
            }
        }
        Ok(Self {
            vertices,
            triangles,
            normals: None,
            uvs: None,
            colors: None,
        })
    }

    /// Attaches per-vertex normals `#V×3` (not normalised here).
    pub fn with_normals(mut self, normals: Vec<[f32; 3]>) -> Result<Self> {
        check_len("vertex normals", self.vertices.len(), normals.len())?;
        check_finite("normal", &normals)?;
        self.normals = Some(normals);
        Ok(self)
    }

    /// Attaches per-vertex texture coordinates `#V×2`.
    pub fn with_uvs(mut self, uvs: Vec<[f32; 2]>) -> Result<Self> {
        check_len("vertex uvs", self.vertices.len(), uvs.len())?;
        check_finite("uv", &uvs)?;
        self.uvs = Some(uvs);
        Ok(self)
    }

    /// Attaches per-vertex RGB colours `#V×3`, components in `[0, 1]`.
    pub fn with_colors(mut self, colors: Vec<[f32; 3]>) -> Result<Self> {
        check_len("vertex colors", self.vertices.len(), colors.len())?;
        check_finite("color", &colors)?;
        self.colors = Some(colors);
        Ok(self)
    }

    /// Replaces the positions, keeping topology and attributes (e.g. a deformed template).
    pub fn with_vertices(mut self, vertices: Vec<[f32; 3]>) -> Result<Self> {
        check_len("vertices", self.vertices.len(), vertices.len())?;
        check_finite("vertex", &vertices)?;
        self.vertices = vertices;
        Ok(self)
    }

    /// Vertex positions, `#V×3`.
    pub fn vertices(&self) -> &[[f32; 3]] {
        &self.vertices
    }

    /// Triangles as vertex indices, `#F×3`.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Per-vertex normals `#V×3`, when present.
    pub fn normals(&self) -> Option<&[[f32; 3]]> {
        self.normals.as_deref()
    }

    /// Per-vertex texture coordinates `#V×2`, when present.
    pub fn uvs(&self) -> Option<&[[f32; 2]]> {
        self.uvs.as_deref()
    }

    /// Per-vertex colours `#V×3`, when present.
    pub fn colors(&self) -> Option<&[[f32; 3]]> {
        self.colors.as_deref()
    }

    /// Number of vertices `#V`.
    pub fn vertex_count(&self) -> usize {
        self.vertices.len()
    }

    /// Number of triangles `#F`.
    pub fn face_count(&self) -> usize {
        self.triangles.len()
    }

    /// True when the mesh has no triangles.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// The positions of triangle `face`'s three corners.
    ///
    /// # Panics
    /// If `face >= #F` (an internal index, never user input).
    pub fn triangle_positions(&self, face: usize) -> [[f32; 3]; 3] {
        self.triangles[face].map(|v| self.vertices[v as usize])
    }

    /// The same mesh without degenerate faces (a repeated vertex index) and without repeated
    /// copies of a face (the same three vertices, in any order); vertices are kept.
    ///
    /// ```
    /// use meshgnn_geometry::TriMesh;
    /// let v = vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    /// let mesh = TriMesh::new(v, vec![[0, 1, 2], [0, 0, 1], [1, 2, 0]])?;
    /// assert_eq!(mesh.without_degenerate_faces().triangles(), &[[0, 1, 2]]);
    /// # Ok::<(), meshgnn_geometry::Error>(())
    /// ```
    pub fn without_degenerate_faces(&self) -> Self {
        let mut seen = std::collections::HashSet::with_capacity(self.triangles.len());
        let triangles = self
            .triangles
            .iter()
            .copied()
            .filter(|&[a, b, c]| a != b && b != c && a != c)
            .filter(|t| {
                let mut key = *t;
                key.sort_unstable();
                seen.insert(key)
            })
            .collect();
        Self {
            triangles,
            ..self.clone()
        }
    }

    /// The same mesh, attributes included, with a subset of its own faces instead.
    pub(crate) fn with_faces_of_its_own(&self, triangles: Vec<[u32; 3]>) -> Self {
        Self {
            triangles,
            ..self.clone()
        }
    }

    /// Splits the mesh into its parts: `(vertices, triangles, normals, uvs, colors)`.
    #[allow(clippy::type_complexity)]
    pub fn into_parts(
        self,
    ) -> (
        Vec<[f32; 3]>,
        Vec<[u32; 3]>,
        Option<Vec<[f32; 3]>>,
        Option<Vec<[f32; 2]>>,
        Option<Vec<[f32; 3]>>,
    ) {
        (
            self.vertices,
            self.triangles,
            self.normals,
            self.uvs,
            self.colors,
        )
    }
}

/// Fails with [`Error::NonFinite`] at the first NaN or infinite component.
pub(crate) fn check_finite<const N: usize>(
    element: &'static str,
    values: &[[f32; N]],
) -> Result<()> {
    match crate::vec3::first_non_finite(values) {
        Some(index) => Err(Error::NonFinite { element, index }),
        None => Ok(()),
    }
}

/// Fails with [`Error::LengthMismatch`] unless `actual == expected`.
pub(crate) fn check_len(what: &'static str, expected: usize, actual: usize) -> Result<()> {
    if expected == actual {
        Ok(())
    } else {
        Err(Error::LengthMismatch {
            what,
            expected,
            actual,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn triangle() -> Vec<[f32; 3]> {
        vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    }

    #[test]
    fn rejects_out_of_range_index_naming_the_triangle() {
        let err = TriMesh::new(triangle(), vec![[0, 1, 2], [0, 1, 3]]).unwrap_err();
        assert!(matches!(
            err,
            Error::IndexOutOfRange {
                index: 1,
                value: 3,
                count: 3,
                ..
            }
        ));
    }

    #[test]
    fn rejects_nan_naming_the_vertex() {
        let mut v = triangle();
        v[2][1] = f32::NAN;
        let err = TriMesh::new(v, vec![]).unwrap_err();
        assert!(matches!(
            err,
            Error::NonFinite {
                element: "vertex",
                index: 2
            }
        ));
    }

    #[test]
    fn attributes_must_match_vertex_count() {
        let mesh = TriMesh::new(triangle(), vec![[0, 1, 2]]).unwrap();
        assert!(mesh.clone().with_normals(vec![[0.0, 0.0, 1.0]; 2]).is_err());
        assert!(mesh.with_uvs(vec![[0.0; 2]; 3]).is_ok());
    }
}
