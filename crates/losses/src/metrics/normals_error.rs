//! Normal error NE between two triangle meshes (thesis eq. 6.15), by face nearest neighbours.

use crate::metrics::normal_consistency::{NormalOrientation, directed_normal_error};
use crate::point_index::PointIndex;
use crate::{Error, Result};
use meshgnn_geometry::{TriMesh, face_normals};

/// Barycentres `#F×3` and unit normals `#F×3` of the non-degenerate faces of `mesh`.
fn face_barycentres_and_normals(mesh: &TriMesh) -> (Vec<[f32; 3]>, Vec<[f32; 3]>) {
    let normals = face_normals(mesh);
    mesh.triangles()
        .iter()
        .enumerate()
        .filter_map(|(f, _)| {
            let n = *normals.get(f)?;
            if n == [0.0; 3] {
                return None;
            }
            let [a, b, c] = mesh.triangle_positions(f);
            let centre = std::array::from_fn(|k| {
                ((f64::from(a[k]) + f64::from(b[k]) + f64::from(c[k])) / 3.0) as f32
            });
            Some((centre, n))
        })
        .unzip()
}

/// Eq. 6.15: `NE = mean_{t∈F} (1 − cos(n_t, n_{NN(t, F_s)})) + mean_{q∈F_s} (1 − cos(n_q,
/// n_{NN(q, F)}))`, where a face's nearest neighbour is the face of the other mesh whose
/// barycentre is nearest to its barycentre, and normals are oriented face normals (eq. 6.15
/// divides its first sum by |P|; it sums over faces, so we divide by |F|). Degenerate faces
/// (zero area) have no normal and are skipped. Dimensionless, in [0, 4]; 0 for identical meshes.
///
/// Fails with [`Error::Empty`] when a mesh has no non-degenerate face.
///
/// ```
/// use meshgnn_geometry::icosphere;
/// use meshgnn_losses::metrics::normals_error;
/// let sphere = icosphere(2);
/// assert!(normals_error(&sphere, &sphere)? < 1e-12); // 0 up to rounding
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn normals_error(original: &TriMesh, simplified: &TriMesh) -> Result<f64> {
    let (ca, na) = face_barycentres_and_normals(original);
    let (cb, nb) = face_barycentres_and_normals(simplified);
    if ca.is_empty() {
        return Err(Error::Empty {
            what: "non-degenerate faces of the original mesh",
        });
    }
    if cb.is_empty() {
        return Err(Error::Empty {
            what: "non-degenerate faces of the simplified mesh",
        });
    }
    let (tree_a, tree_b) = rayon::join(|| PointIndex::new(&ca), || PointIndex::new(&cb));
    let o = NormalOrientation::Oriented;
    let (f, r) = rayon::join(
        || directed_normal_error(&ca, &na, &tree_b, &nb, o),
        || directed_normal_error(&cb, &nb, &tree_a, &na, o),
    );
    Ok(f + r)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flipped_mesh_scores_four() {
        let v = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let up = TriMesh::new(v.clone(), vec![[0, 1, 2]]).unwrap();
        let down = TriMesh::new(v, vec![[0, 2, 1]]).unwrap();
        assert!(normals_error(&up, &up).unwrap() < 1e-12);
        assert!((normals_error(&up, &down).unwrap() - 4.0).abs() < 1e-12);
    }

    #[test]
    fn hand_computed_tilted_face() {
        // Original: one face in z = 0 (normal +z) and one far away in x = 10 (normal +x).
        // Simplified: only the first face, tilted 90° about x (normal -y).
        let v = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [10.0, 0.0, 0.0],
            [10.0, 1.0, 0.0],
            [10.0, 0.0, 1.0],
        ];
        let original = TriMesh::new(v, vec![[0, 1, 2], [3, 4, 5]]).unwrap();
        let s = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
        let simplified = TriMesh::new(s, vec![[0, 1, 2]]).unwrap();
        // every cosine against -y is 0: forward (1 + 1) / 2 = 1, reverse 1.
        let ne = normals_error(&original, &simplified).unwrap();
        assert!((ne - 2.0).abs() < 1e-6, "{ne}");
    }
}
