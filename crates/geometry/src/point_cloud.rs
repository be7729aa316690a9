//! [`PointCloud`]: unordered points with optional normals.

use crate::error::Result;
use crate::tri_mesh::{check_finite, check_len};

/// A point cloud `#P×3` with optional per-point normals `#P×3`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PointCloud {
    points: Vec<[f32; 3]>,
    normals: Option<Vec<[f32; 3]>>,
}

impl PointCloud {
    /// A cloud from `points: #P×3`; fails on a non-finite coordinate.
    ///
    /// ```
    /// use meshgnn_geometry::PointCloud;
    /// let cloud = PointCloud::new(vec![[0.0; 3], [1.0, 2.0, 3.0]])?;
    /// assert_eq!(cloud.len(), 2);
    /// assert!(PointCloud::new(vec![[f32::NAN, 0.0, 0.0]]).is_err());
    /// # Ok::<(), meshgnn_geometry::Error>(())
    /// ```
    pub fn new(points: Vec<[f32; 3]>) -> Result<Self> {
        check_finite("point", &points)?;
        Ok(Self {
            points,
            normals: None,
        })
    }

    /// Attaches per-point normals `#P×3`.
    pub fn with_normals(mut self, normals: Vec<[f32; 3]>) -> Result<Self> {
        check_len("point normals", self.points.len(), normals.len())?;
        check_finite("normal", &normals)?;
        self.normals = Some(normals);
        Ok(self)
    }

    /// The points, `#P×3`.
    pub fn points(&self) -> &[[f32; 3]] {
        &self.points
    }

    /// Per-point normals `#P×3`, when present.
    pub fn normals(&self) -> Option<&[[f32; 3]]> {
        self.normals.as_deref()
    }

    /// Number of points `#P`.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True when the cloud has no points.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Splits the cloud into `(points, normals)`.
    pub fn into_parts(self) -> (Vec<[f32; 3]>, Option<Vec<[f32; 3]>>) {
        (self.points, self.normals)
    }
}

impl From<crate::TriMesh> for PointCloud {
    /// The mesh's vertices (and vertex normals, when present) as a cloud.
    fn from(mesh: crate::TriMesh) -> Self {
        let (points, _, normals, _, _) = mesh.into_parts();
        Self { points, normals }
    }
}
