//! The lumped (diagonal) mass matrix of a triangle mesh: the area each vertex represents,
//! the `M` of the generalised eigenproblem `L x = λ M x` used for the Laplacian eigenvectors
//! (LE of thesis eq. 6.16).
//!
//! # Conventions
//! Barycentric lumping: `M_ii = Σ_{f ∋ i} A_f / 3`. Unlike the mixed-Voronoi areas it is
//! positive for every vertex of a non-degenerate face even on obtuse meshes, sums exactly to
//! the surface area, and converges to the same operator under refinement. Unreferenced
//! vertices get mass 0. Accumulated in `f64` in face order (independent of the thread count).

use crate::TriMesh;
use crate::face_normals::face_areas;

/// Diagonal of the lumped mass matrix, `#V`, in squared mesh units.
///
/// ```
/// use meshgnn_geometry::{TriMesh, lumped_mass_matrix};
/// let v = vec![[0.0; 3], [2.0, 0.0, 0.0], [0.0, 3.0, 0.0], [9.0; 3]];
/// let mesh = TriMesh::new(v, vec![[0, 1, 2]])?;
/// assert_eq!(lumped_mass_matrix(&mesh), vec![1.0, 1.0, 1.0, 0.0]);
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn lumped_mass_matrix(mesh: &TriMesh) -> Vec<f64> {
    let mut mass = vec![0.0f64; mesh.vertex_count()];
    for (t, area) in mesh.triangles().iter().zip(face_areas(mesh)) {
        for &v in t {
            mass[v as usize] += area / 3.0;
        }
    }
    mass
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{face_areas, grid_plane};

    #[test]
    fn masses_sum_to_the_surface_area() {
        let plane = grid_plane(7, 5);
        let total: f64 = lumped_mass_matrix(&plane).iter().sum();
        assert!((total - 1.0).abs() < 1e-12);
        assert!((total - face_areas(&plane).iter().sum::<f64>()).abs() < 1e-12);
        // An interior vertex of the uniform grid touches 6 faces of area 1/(2·35).
        let interior = lumped_mass_matrix(&plane)[8 + 1];
        // f32 grid coordinates: relative rounding of about 1e-7.
        assert!((interior - 6.0 / 70.0 / 3.0).abs() < 1e-7 * interior);
    }
}
