//! Per-face unit normals and areas.
//!
//! The normal of a counter-clockwise triangle `(a, b, c)` is `(b − a) × (c − a) / |…|` and its
//! area half that cross product's length (computed in `f64`). Used by the vertex normals, the
//! lumped mass matrix, surface sampling and the normal error NE of thesis eq. 6.15.

use rayon::prelude::*;

use crate::TriMesh;
use crate::vec3::{norm, triangle_cross, unit_f32};

/// Unit normal of every face, `#F×3`, by the right-hand rule (outward for counter-clockwise
/// faces); zero for a degenerate face (zero area or a repeated vertex).
///
/// ```
/// use meshgnn_geometry::{TriMesh, face_normals};
/// let v = vec![[0.0; 3], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [1.0, 0.0, 0.0]];
/// let mesh = TriMesh::new(v, vec![[0, 1, 2], [0, 3, 1]])?;
/// assert_eq!(face_normals(&mesh), vec![[0.0, 0.0, 1.0], [0.0, 0.0, 0.0]]);
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn face_normals(mesh: &TriMesh) -> Vec<[f32; 3]> {
    let vertices = mesh.vertices();
    mesh.triangles()
        .par_iter()
        .map(|t| unit_f32(triangle_cross(t.map(|v| vertices[v as usize]))))
        .collect()
}

/// Area of every face, `#F`, in squared mesh units (`f64`); zero for degenerate faces.
///
/// ```
/// use meshgnn_geometry::{TriMesh, face_areas};
/// let v = vec![[0.0; 3], [2.0, 0.0, 0.0], [0.0, 3.0, 0.0]];
/// let mesh = TriMesh::new(v, vec![[0, 1, 2]])?;
/// assert_eq!(face_areas(&mesh), vec![3.0]);
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn face_areas(mesh: &TriMesh) -> Vec<f64> {
    let vertices = mesh.vertices();
    mesh.triangles()
        .par_iter()
        .map(|t| 0.5 * norm(triangle_cross(t.map(|v| vertices[v as usize]))))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{icosphere, subdivided_cube};

    #[test]
    fn cube_face_normals_are_exactly_the_axes() {
        let cube = subdivided_cube(4);
        let normals = face_normals(&cube);
        for (f, n) in normals.iter().enumerate() {
            let [a, b, c] = cube.triangle_positions(f);
            let centroid = [0, 1, 2].map(|i| (a[i] + b[i] + c[i]) / 3.0);
            // The axis of the face is the coordinate at ±1 shared by all corners.
            let axis = (0..3)
                .find(|&i| a[i].abs() == 1.0 && a[i] == b[i] && b[i] == c[i])
                .unwrap();
            let mut expected = [0.0f32; 3];
            expected[axis] = centroid[axis].signum();
            assert_eq!(*n, expected, "face {f}");
        }
    }

    #[test]
    fn sphere_areas_sum_to_nearly_four_pi() {
        let total: f64 = face_areas(&icosphere(5)).iter().sum();
        let exact = 4.0 * std::f64::consts::PI;
        // The inscribed polyhedron is slightly smaller than the sphere.
        assert!(total < exact && total > exact * 0.998, "{total}");
    }
}
