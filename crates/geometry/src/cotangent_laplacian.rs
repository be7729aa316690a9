//! The cotangent Laplacian of a triangle mesh: eq. 2.13 (`Δ = D − W`) with the cotangent
//! weights of the P1 finite-element stiffness matrix (Pinkall and Polthier 1993; Meyer,
//! Desbrun, Schröder and Barr 2003), the operator behind the Laplacian eigenvectors of the LE
//! metric (thesis eq. 6.16).
//!
//! # Conventions
//! - Positive semi-definite `L = D − W` with `w_ij = (cot α_ij + cot β_ij) / 2`, the angles
//!   opposite edge `ij` in its (one or two) faces, and `D_ii = Σ_j w_ij`; `L·1 = 0`.
//!   Weights may be negative for obtuse angles; `L` is still PSD (a stiffness matrix).
//! - Degenerate faces (a repeated vertex or zero area, see [`crate::degenerate_faces`])
//!   contribute nothing, so `L` stays finite.
//! - `faer::sparse::SparseColMat<usize, f64>`, both triangles stored, entries summed in face
//!   order (deterministic).

use faer::sparse::{SparseColMat, Triplet};
use rayon::prelude::*;

use crate::TriMesh;
use crate::degenerate_faces::is_zero_area;
use crate::error::{Error, Result};
use crate::vec3::{cross, dot, norm, sub, to_f64};

/// The cotangent Laplacian `#V×#V` (see the module conventions).
///
/// ```
/// use meshgnn_geometry::{TriMesh, cotangent_laplacian};
/// // A right isosceles triangle: the right angle at vertex 0 faces edge (1, 2), cot = 0;
/// // the 45° angles give w_01 = w_02 = 1/2.
/// let v = vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
/// let l = cotangent_laplacian(&TriMesh::new(v, vec![[0, 1, 2]])?)?.to_dense();
/// assert!((l[(0, 1)] + 0.5).abs() < 1e-15 && l[(1, 2)].abs() < 1e-15);
/// assert!((l[(0, 0)] - 1.0).abs() < 1e-15);
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn cotangent_laplacian(mesh: &TriMesh) -> Result<SparseColMat<usize, f64>> {
    let vertices = mesh.vertices();
    let per_face: Vec<[Triplet<usize, usize, f64>; 9]> = mesh
        .triangles()
        .par_iter()
        .filter_map(|t| {
            let corners = t.map(|v| vertices[v as usize]);
            if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || is_zero_area(corners) {
                return None;
            }
            let p = corners.map(to_f64);
            let mut entries = [Triplet::new(0, 0, 0.0); 9];
            for i in 0..3 {
                // Angle at corner i faces the edge (j, k).
                let (j, k) = ((i + 1) % 3, (i + 2) % 3);
                let (u, w) = (sub(p[j], p[i]), sub(p[k], p[i]));
                let half_cot = 0.5 * dot(u, w) / norm(cross(u, w));
                let (a, b) = (t[j] as usize, t[k] as usize);
                entries[3 * i] = Triplet::new(a, b, -half_cot);
                entries[3 * i + 1] = Triplet::new(b, a, -half_cot);
                entries[3 * i + 2] = Triplet::new(t[i] as usize, t[i] as usize, 0.0);
            }
            // Diagonal: each vertex gets the weights of its two edges in this face.
            for i in 0..3 {
                let (j, k) = ((i + 1) % 3, (i + 2) % 3);
                // Edge (i, j) is opposite corner k, edge (i, k) opposite corner j.
                let weight = -(entries[3 * k].val + entries[3 * j].val);
                entries[3 * i + 2] = Triplet::new(t[i] as usize, t[i] as usize, weight);
            }
            Some(entries)
        })
        .collect();
    let triplets: Vec<Triplet<usize, usize, f64>> = per_face.into_iter().flatten().collect();
    let n = mesh.vertex_count();
    SparseColMat::try_new_from_triplets(n, n, &triplets).map_err(|e| Error::Solver {
        solver: "cotangent laplacian assembly",
        message: format!("{e:?}"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{grid_plane, icosphere};
    use faer::Side;
    use proptest::prelude::*;

    #[test]
    fn annihilates_linear_functions_at_interior_vertices_of_a_flat_grid() {
        // Perturb the interior of the grid so that the test is not only about a regular stencil.
        let plane = grid_plane(6, 5);
        let moved: Vec<[f32; 3]> = plane
            .vertices()
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let interior = p[0] > 0.0 && p[0] < 1.0 && p[1] > 0.0 && p[1] < 1.0;
                let d = if interior {
                    0.03 * ((i * 37 % 11) as f32 / 11.0 - 0.5)
                } else {
                    0.0
                };
                [p[0] + d, p[1] - d, 0.0]
            })
            .collect();
        let mesh = plane.with_vertices(moved).unwrap();
        let l = cotangent_laplacian(&mesh).unwrap().to_dense();
        let f: Vec<f64> = mesh
            .vertices()
            .iter()
            .map(|p| 3.0 * f64::from(p[0]) - 2.0 * f64::from(p[1]) + 1.0)
            .collect();
        for (i, p) in mesh.vertices().iter().enumerate() {
            let interior = p[0] > 0.0 && p[0] < 1.0 && p[1] > 0.0 && p[1] < 1.0;
            let lf: f64 = (0..f.len()).map(|j| l[(i, j)] * f[j]).sum();
            if interior {
                assert!(lf.abs() < 1e-5, "vertex {i}: {lf}");
            }
        }
    }

    #[test]
    fn symmetric_psd_with_constant_kernel_on_a_sphere() {
        let l = cotangent_laplacian(&icosphere(2)).unwrap().to_dense();
        let n = l.nrows();
        for i in 0..n {
            assert!((0..n).map(|j| l[(i, j)]).sum::<f64>().abs() < 1e-12);
            for j in 0..n {
                assert_eq!(l[(i, j)], l[(j, i)]);
            }
        }
        let values = l.self_adjoint_eigenvalues(Side::Lower).unwrap();
        assert!(values[0].abs() < 1e-10 && values[1] > 1e-3);
    }

    proptest! {
        #[test]
        fn rows_sum_to_zero_and_psd_on_random_meshes(
            points in prop::collection::vec(prop::array::uniform3(-10.0f32..10.0), 4..20),
            faces in prop::collection::vec(prop::array::uniform3(0u32..20), 1..30),
        ) {
            let n = points.len() as u32;
            let faces = faces.into_iter().map(|t| t.map(|v| v % n)).collect();
            let mesh = TriMesh::new(points, faces).unwrap();
            let l = cotangent_laplacian(&mesh).unwrap().to_dense();
            let scale = (0..l.nrows()).map(|i| l[(i, i)].abs()).fold(1.0, f64::max);
            for i in 0..l.nrows() {
                let row: f64 = (0..l.ncols()).map(|j| l[(i, j)]).sum();
                prop_assert!(row.abs() < 1e-9 * scale, "row {} sums to {}", i, row);
            }
            let values = l.self_adjoint_eigenvalues(Side::Lower).unwrap();
            prop_assert!(values[0] > -1e-9 * scale);
            let g = crate::combinatorial_laplacian_of_mesh(&mesh).unwrap().to_dense();
            for i in 0..g.nrows() {
                prop_assert_eq!((0..g.ncols()).map(|j| g[(i, j)]).sum::<f64>(), 0.0);
            }
        }
    }
}
