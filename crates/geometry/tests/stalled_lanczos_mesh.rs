//! The mesh on which block Lanczos with a shift below zero stalled at its 852-vector basis cap
//! (QEM's 10 % of a synthetic creature; `meshsimplify eval` failed on it before the dense
//! fallback existed): every pair is found, with the eigenvalues of a dense solve of the same
//! generalised problem `L x = λ M x`.

// Test code: a panic in a helper is a failed test, as in the test functions.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use faer::{Mat, Side};
use meshgnn_geometry::{
    cotangent_laplacian, laplacian_eigenvectors, lumped_mass_matrix, read_mesh,
    unit_sphere_normalization,
};
use std::path::PathBuf;

#[test]
fn the_mesh_that_stalled_lanczos_gets_the_dense_solution() {
    // QEM's 10 % of a synthetic creature (data-fixtures/README.md): 1 029 vertices, closed.
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data-fixtures/solver/creatures_b_qem10.ply");
    let read = read_mesh(&path).unwrap();
    assert_eq!(read.vertex_count(), 1029);
    // In the unit sphere, as the Laplacian error sees it (where the stall was found).
    let unit = unit_sphere_normalization(read.vertices())
        .unwrap()
        .apply(read.vertices());
    let mesh = read.with_vertices(unit).unwrap();
    let k = 150;
    let pairs = laplacian_eigenvectors(&mesh, k).unwrap();
    assert_eq!(pairs.values.len(), k);
    assert!(pairs.values.windows(2).all(|w| w[0] <= w[1]));
    assert!(pairs.values[0].abs() < 1e-9 && pairs.values[1] > 1e-6);
    let laplacian = cotangent_laplacian(&mesh).unwrap();
    let mass = lumped_mass_matrix(&mesh);
    let n = mesh.vertex_count();
    // The dense reference: the eigenvalues of M^{-1/2} L M^{-1/2}.
    let mut a = Mat::<f64>::zeros(n, n);
    for col in 0..n {
        let rows = laplacian.symbolic().row_idx_of_col_raw(col);
        for (&row, &value) in rows.iter().zip(laplacian.val_of_col(col)) {
            a[(row, col)] = value / (mass[row] * mass[col]).sqrt();
        }
    }
    let dense = a.self_adjoint_eigen(Side::Lower).unwrap();
    for i in 1..k {
        let expected = dense.S()[i];
        assert!(
            (pairs.values[i] - expected).abs() <= 1e-8 * expected,
            "λ{i} = {} against {expected}",
            pairs.values[i]
        );
    }
    // Every pair satisfies L x = λ M x to the solver's precision, relative to its terms (pair 0
    // is the null vector, its L x rounding alone), and Xᵀ M X = I.
    let x = &pairs.vectors;
    for i in 1..k {
        let mut lx = vec![0.0; n];
        for col in 0..n {
            let rows = laplacian.symbolic().row_idx_of_col_raw(col);
            for (&row, &value) in rows.iter().zip(laplacian.val_of_col(col)) {
                lx[row] += value * x[(col, i)];
            }
        }
        let norm = |v: &dyn Fn(usize) -> f64| (0..n).map(|j| v(j).powi(2)).sum::<f64>().sqrt();
        let residual = norm(&|v| lx[v] - pairs.values[i] * mass[v] * x[(v, i)]);
        let scale = norm(&|v| lx[v]) + pairs.values[i] * norm(&|v| mass[v] * x[(v, i)]);
        assert!(
            residual <= 1e-6 * scale,
            "pair {i}: residual {residual} of {scale}"
        );
    }
    for i in 0..k {
        for j in 0..=i {
            let product: f64 = (0..n).map(|v| x[(v, i)] * mass[v] * x[(v, j)]).sum();
            let expected = if i == j { 1.0 } else { 0.0 };
            assert!(
                (product - expected).abs() < 1e-9,
                "x{i}ᵀ M x{j} = {product}"
            );
        }
    }
}
