//! The face of a triangle mesh closest to a point, exactly, through a k-d tree over the face
//! centroids: the nearest centroid's face gives a first distance `d`; no face whose centroid
//! lies farther than `d` plus the largest centroid-to-corner distance (the *reach*) can be
//! closer, so the faces within that ball are all compared (the closest point of each by
//! [`closest_point_on_triangle`]). Used for COMA's up-sampling weights (thesis ch. 3.3.4,
//! [`crate::pooling_matrices`]) and by the neural mesh simplifier to tell a hole's patch that
//! lies along the input's surface from one across an opening.

use meshgnn_geometry::{SpatialIndex, TriMesh, squared_distance};

use crate::closest_point_on_triangle::closest_point_on_triangle;
use crate::error::{Error, Result};

/// A mesh's faces, indexed for closest-face queries (module docs). The query time grows with
/// the number of centroids within the reach of the nearest one: a mesh with one face much
/// larger than the others pays for it.
#[derive(Debug, Clone)]
pub struct ClosestFace<'a> {
    mesh: &'a TriMesh,
    /// The indexed faces, in the order of the centroids' indices.
    faces: Vec<u32>,
    centroids: SpatialIndex,
    reach: f32,
}

/// The answer of [`ClosestFace::query`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FacePoint {
    /// The closest face (the lowest index among equally close ones).
    pub face: u32,
    /// Barycentric weights of the closest point on it (non-negative, summing to 1).
    pub weights: [f64; 3],
    /// Squared distance from the query point.
    pub squared_distance: f64,
}

impl<'a> ClosestFace<'a> {
    /// Indexes every face of `mesh`; errors on a mesh without faces.
    ///
    /// ```
    /// use meshgnn_geometry::TriMesh;
    /// use meshgnn_graph::ClosestFace;
    /// let square = TriMesh::new(
    ///     vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
    ///     vec![[0, 1, 2], [0, 2, 3]],
    /// )?;
    /// let closest = ClosestFace::new(&square)?;
    /// let hit = closest.query(&[0.2, 0.7, 0.5], &mut Vec::new());
    /// assert_eq!(hit.face, 1);
    /// assert!((hit.squared_distance - 0.25).abs() < 1e-12);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn new(mesh: &'a TriMesh) -> Result<Self> {
        Self::among(mesh, (0..mesh.face_count() as u32).collect())
    }

    /// Indexes only `faces` of `mesh` (indices into its triangles): queries answer the
    /// closest of them. Errors when `faces` is empty or holds an index out of range.
    ///
    /// ```
    /// use meshgnn_geometry::TriMesh;
    /// use meshgnn_graph::ClosestFace;
    /// // Two unit triangles, one at z = 0 and one at z = 5.
    /// let pair = TriMesh::new(
    ///     vec![
    ///         [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0],
    ///         [0.0, 0.0, 5.0], [1.0, 0.0, 5.0], [0.0, 1.0, 5.0],
    ///     ],
    ///     vec![[0, 1, 2], [3, 4, 5]],
    /// )?;
    /// let upper = ClosestFace::among(&pair, vec![1])?;
    /// let hit = upper.query(&[0.2, 0.2, 1.0], &mut Vec::new());
    /// assert_eq!(hit.face, 1);
    /// assert!((hit.squared_distance - 16.0).abs() < 1e-9);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn among(mesh: &'a TriMesh, faces: Vec<u32>) -> Result<Self> {
        if faces.is_empty() {
            return Err(Error::Empty {
                what: "faces to find the closest of",
            });
        }
        if let Some(&f) = faces.iter().find(|&&f| f as usize >= mesh.face_count()) {
            return Err(Error::InvalidParameter {
                name: "faces",
                message: format!("face {f} is outside the mesh's {} faces", mesh.face_count()),
            });
        }
        let v = mesh.vertices();
        let corners = |f: u32| mesh.triangles()[f as usize].map(|i| v[i as usize]);
        let centroids: Vec<[f32; 3]> = faces
            .iter()
            .map(|&f| {
                let c = corners(f);
                std::array::from_fn(|k| (c[0][k] + c[1][k] + c[2][k]) / 3.0)
            })
            .collect();
        let reach = faces
            .iter()
            .zip(&centroids)
            .map(|(&f, centroid)| {
                corners(f)
                    .iter()
                    .map(|corner| squared_distance(centroid, corner))
                    .fold(0.0f32, f32::max)
                    .sqrt()
            })
            .fold(0.0f32, f32::max);
        Ok(Self {
            mesh,
            centroids: SpatialIndex::new(&centroids)?,
            faces,
            reach,
        })
    }

    /// The face closest to `p` and the closest point on it. `scratch` is reused between
    /// queries.
    pub fn query(&self, p: &[f32; 3], scratch: &mut Vec<(f32, u32)>) -> FacePoint {
        self.centroids.nearest(p, 1, None, scratch);
        let mut best = self.face_point(p, scratch.first().map_or(0, |n| n.1));
        self.centroids_within(p, best.squared_distance.sqrt(), scratch);
        for &(_, slot) in scratch.iter() {
            let hit = self.face_point(p, slot);
            if hit.squared_distance < best.squared_distance
                || (hit.squared_distance == best.squared_distance && hit.face < best.face)
            {
                best = hit;
            }
        }
        best
    }

    /// The faces within `radius` of `p`, each with its closest point, in no set order.
    /// `scratch` is reused between queries.
    ///
    /// ```
    /// use meshgnn_geometry::TriMesh;
    /// use meshgnn_graph::ClosestFace;
    /// let square = TriMesh::new(
    ///     vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
    ///     vec![[0, 1, 2], [0, 2, 3]],
    /// )?;
    /// let closest = ClosestFace::new(&square)?;
    /// let mut scratch = Vec::new();
    /// // Beside the diagonal both faces are near; a point off the lower right corner is near
    /// // only the face holding it.
    /// assert_eq!(closest.within(&[0.5, 0.5, 0.1], 0.2, &mut scratch).count(), 2);
    /// let off_corner = [1.2, -0.1, 0.0];
    /// let near: Vec<u32> =
    ///     closest.within(&off_corner, 0.3, &mut scratch).map(|h| h.face).collect();
    /// assert_eq!(near, vec![0]);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn within<'s>(
        &'s self,
        p: &'s [f32; 3],
        radius: f64,
        scratch: &'s mut Vec<(f32, u32)>,
    ) -> impl Iterator<Item = FacePoint> + 's {
        self.centroids_within(p, radius, scratch);
        scratch
            .iter()
            .map(|&(_, slot)| self.face_point(p, slot))
            .filter(move |hit| hit.squared_distance <= radius * radius)
    }

    /// Fills `scratch` with the centroids (distance, slot) that may hold a face within
    /// `radius` of `p`: those within `radius` plus the reach.
    fn centroids_within(&self, p: &[f32; 3], radius: f64, scratch: &mut Vec<(f32, u32)>) {
        let ball = (radius as f32 + self.reach) * (1.0 + 1e-5) + 1e-12;
        self.centroids.within(p, ball * ball, None, scratch);
    }

    /// The closest point to `p` on the indexed face at `slot`.
    fn face_point(&self, p: &[f32; 3], slot: u32) -> FacePoint {
        let face = self.faces[slot as usize];
        let v = self.mesh.vertices();
        let corners = self.mesh.triangles()[face as usize].map(|i| v[i as usize].map(f64::from));
        let (weights, squared_distance) =
            closest_point_on_triangle(p.map(f64::from), corners[0], corners[1], corners[2]);
        FacePoint {
            face,
            weights,
            squared_distance,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshgnn_geometry::icosphere;

    #[test]
    fn matches_a_search_over_every_face() {
        let sphere = icosphere(2);
        let closest = ClosestFace::new(&sphere).unwrap();
        let mut scratch = Vec::new();
        let mut state = 12345u64;
        let mut coordinate = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((state >> 33) as f64 / (1u64 << 31) as f64) * 3.0 - 1.5
        };
        let mut points_near_faces = 0;
        for _ in 0..300 {
            let p = [coordinate(), coordinate(), coordinate()].map(|x| x as f32);
            let q = p.map(f64::from);
            let brute = sphere
                .triangles()
                .iter()
                .map(|t| {
                    let c = t.map(|i| sphere.vertices()[i as usize].map(f64::from));
                    closest_point_on_triangle(q, c[0], c[1], c[2]).1
                })
                .fold(f64::INFINITY, f64::min);
            let hit = closest.query(&p, &mut scratch);
            assert!((hit.squared_distance - brute).abs() <= 1e-12, "{p:?}");
            // The faces within a radius: those a search over every face finds, none else.
            let near_radius = 0.3;
            let mut near: Vec<u32> = closest
                .within(&p, near_radius, &mut scratch)
                .map(|h| h.face)
                .collect();
            near.sort_unstable();
            let every: Vec<u32> = (0..sphere.face_count() as u32)
                .filter(|&f| {
                    let t = sphere.triangles()[f as usize];
                    let c = t.map(|i| sphere.vertices()[i as usize].map(f64::from));
                    closest_point_on_triangle(q, c[0], c[1], c[2]).1 <= near_radius * near_radius
                })
                .collect();
            assert_eq!(near, every, "{p:?}");
            points_near_faces += usize::from(!near.is_empty());
            // The icosphere is inscribed in the unit sphere: at most its distance outside.
            let radius = q.iter().map(|x| x * x).sum::<f64>().sqrt();
            if radius > 1.0 {
                assert!(hit.squared_distance.sqrt() >= radius - 1.0 - 1e-6);
            }
        }
        assert!(points_near_faces >= 50, "{points_near_faces}");
    }

    #[test]
    fn no_faces_or_a_face_out_of_range_is_refused() {
        let sphere = icosphere(0);
        assert!(ClosestFace::among(&sphere, Vec::new()).is_err());
        assert!(ClosestFace::among(&sphere, vec![0, 20]).is_err());
        assert!(ClosestFace::new(&TriMesh::default()).is_err());
    }

    #[test]
    fn a_lone_large_face_is_found_beside_small_ones() {
        // A large triangle far below a cluster of small ones: a point under the large one's
        // middle is closest to it although every small centroid is nearer than its centroid.
        let mut vertices = vec![[-50.0, -50.0, 0.0], [50.0, -50.0, 0.0], [0.0, 80.0, 0.0]];
        let mut faces = vec![[0, 1, 2]];
        for k in 0..20u32 {
            let x = k as f32 * 0.1;
            vertices.extend([[x, 20.0, 5.0], [x + 0.05, 20.0, 5.0], [x, 20.05, 5.0]]);
            faces.push([3 + 3 * k, 4 + 3 * k, 5 + 3 * k]);
        }
        let mesh = TriMesh::new(vertices, faces).unwrap();
        let hit = ClosestFace::new(&mesh)
            .unwrap()
            .query(&[0.5, 18.0, 1.0], &mut Vec::new());
        assert_eq!(hit.face, 0);
        assert!((hit.squared_distance - 1.0).abs() < 1e-9);
    }
}
