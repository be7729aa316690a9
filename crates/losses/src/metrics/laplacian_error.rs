//! Laplacian error LE (thesis eq. 6.16): how well a simplified mesh keeps the low-frequency
//! spectrum (the first 150 Laplacian eigenvectors) of the original.
//!
//! # Definition choices
//! The meshes have different vertex counts, so eq. 6.16's `‖φ̂_i − φ_i‖²` needs a common
//! domain. We use:
//! - **Operator.** The cotangent Laplacian with lumped mass `M` (geometry crate's
//!   `laplacian_eigenvectors`): eigenvectors are M-orthonormal, i.e. sampled continuous
//!   eigenfunctions of unit L²-norm on the surface, so they are comparable across resolutions.
//! - **Transfer.** Each simplified eigenvector is read at the original vertices through the
//!   nearest simplified vertex (`φ̂_i ∘ s`, `s(v) = NN(v, V_s)`).
//! - **Matching.** Eigenvectors are matched by order (`i`-th with `i`-th) and sign: `φ̂_i` is
//!   flipped when `⟨φ̂_i ∘ s, φ_i⟩_M < 0` (eigenvectors are defined up to sign).
//! - **Norm and averaging.** `LE = (1/K) Σ_{i<K} ‖φ̂_i ∘ s − φ_i‖²_M`, the M-weighted (area-
//!   weighted) squared error on the original, averaged over the `K = min(150, V_s − 1, V − 1)`
//!   eigenvectors ("MSE over the first 150 eigenvectors"). Dimensionless (unit-norm functions);
//!   0 for identical meshes, about 2 for unrelated functions of unit norm.
//!
//! Limitation: eigenvalues of (near) multiplicity > 1, as on a sphere, make their eigenvectors
//! any rotation within the eigenspace, so order-and-sign matching can report a large error for
//! a faithful simplification of a highly symmetric shape. Scanned and CAD shapes rarely have
//! such symmetry.

use crate::deterministic_sum::deterministic_sum;
use crate::point_index::PointIndex;
use crate::validate::check_points;
use crate::{Error, Result};
use meshgnn_geometry::{TriMesh, laplacian_eigenvectors, lumped_mass_matrix};
use rayon::prelude::*;

/// The number of eigenvectors of eq. 6.16.
pub const LAPLACIAN_EIGENVECTORS: usize = 150;

/// Eq. 6.16 with the comparison of the module docs, over at most `max_eigenvectors`
/// eigenvectors (150 in the thesis). Both meshes must be in the same frame (e.g. normalised by
/// the original's unit sphere).
///
/// Fails when a mesh has no face of positive area or fewer than 2 surface vertices, or when the
/// eigen-solver fails (geometry error).
///
/// ```
/// use meshgnn_geometry::subdivided_cube;
/// use meshgnn_losses::metrics::laplacian_error;
/// let cube = subdivided_cube(4);
/// assert!(laplacian_error(&cube, &cube, 20)? < 1e-12);
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn laplacian_error(
    original: &TriMesh,
    simplified: &TriMesh,
    max_eigenvectors: usize,
) -> Result<f64> {
    check_points("original vertices", original.vertices())?;
    check_points("simplified vertices", simplified.vertices())?;
    let surface = |m: &TriMesh| lumped_mass_matrix(m).iter().filter(|&&x| x > 0.0).count();
    let k = max_eigenvectors
        .min(surface(original).saturating_sub(1))
        .min(surface(simplified).saturating_sub(1));
    if k == 0 {
        return Err(Error::InvalidParameter {
            name: "meshes",
            message: "the Laplacian error needs at least one eigenvector: both meshes need two \
                      or more vertices on faces of positive area and max_eigenvectors >= 1"
                .into(),
        });
    }
    let (a, b) = rayon::join(
        || laplacian_eigenvectors(original, k),
        || laplacian_eigenvectors(simplified, k),
    );
    let of = |what: &'static str| move |error| Error::GeometryOf { what, error };
    let (a, b) = (
        a.map_err(of("original mesh"))?,
        b.map_err(of("simplified mesh"))?,
    );
    let mass = lumped_mass_matrix(original);
    let tree = PointIndex::new(simplified.vertices());
    let transfer: Vec<usize> = tree
        .nearest_all(original.vertices())
        .into_iter()
        .map(|(j, _)| j)
        .collect();
    let k = k.min(a.vectors.ncols()).min(b.vectors.ncols());
    let errors: Vec<f64> = (0..k)
        .into_par_iter()
        .map(|i| {
            let phi: Vec<f64> = a.vectors.col(i).iter().copied().collect();
            let hat: Vec<f64> = b.vectors.col(i).iter().copied().collect();
            let moved: Vec<f64> = transfer
                .iter()
                .map(|&j| hat.get(j).copied().unwrap_or(0.0))
                .collect();
            let term = |v: usize, sign: f64| -> (f64, f64) {
                let m = mass.get(v).copied().unwrap_or(0.0);
                let (p, h) = (
                    phi.get(v).copied().unwrap_or(0.0),
                    moved.get(v).copied().unwrap_or(0.0),
                );
                (m * p * h, m * (sign * h - p) * (sign * h - p))
            };
            let inner = deterministic_sum(phi.len(), |v| term(v, 1.0).0);
            let sign = if inner < 0.0 { -1.0 } else { 1.0 };
            deterministic_sum(phi.len(), |v| term(v, sign).1)
        })
        .collect();
    Ok(errors.iter().sum::<f64>() / k as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshgnn_geometry::{grid_plane, subdivided_cube};

    #[test]
    fn identical_meshes_and_vertex_order() {
        let plane = grid_plane(8, 5);
        assert!(laplacian_error(&plane, &plane, 10).unwrap() < 1e-12);
    }

    #[test]
    fn coarser_grid_is_close_but_not_equal() {
        // A 2:1 rectangle has a simple spectrum (no multiplicities among the first modes).
        let scale = |m: TriMesh| {
            let v: Vec<[f32; 3]> = m
                .vertices()
                .iter()
                .map(|p| [2.0 * p[0], p[1], 0.0])
                .collect();
            m.with_vertices(v).unwrap()
        };
        let fine = scale(grid_plane(40, 20));
        let coarse = scale(grid_plane(20, 10));
        let very_coarse = scale(grid_plane(6, 3));
        let e1 = laplacian_error(&fine, &coarse, 6).unwrap();
        let e2 = laplacian_error(&fine, &very_coarse, 6).unwrap();
        assert!(e1 > 0.0 && e1 < 0.05, "{e1}");
        assert!(e2 > e1, "{e2} <= {e1}");
    }

    #[test]
    fn degenerate_input_is_an_error() {
        let cube = subdivided_cube(2);
        let v = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
        let flat = TriMesh::new(v, vec![[0, 1, 2]]).unwrap();
        assert!(laplacian_error(&cube, &flat, 10).is_err());
    }
}
