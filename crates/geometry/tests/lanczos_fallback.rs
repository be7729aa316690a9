//! A mesh on which block Lanczos stalls at its basis cap: the dense fallback answers, with
//! the eigenpairs of the generalised problem `L x = λ M x`.

// Test code: a panic in a helper is a failed test, as in the test functions.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use meshgnn_geometry::{
    cotangent_laplacian, laplacian_eigenvectors, lumped_mass_matrix, read_mesh,
    unit_sphere_normalization,
};
use std::path::PathBuf;

#[test]
fn a_stalled_lanczos_falls_back_to_the_dense_solve() {
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
    // Every pair satisfies L x = λ M x (relative to its terms; pair 0 is the null vector,
    // its L x rounding alone), and Xᵀ M X = I.
    let laplacian = cotangent_laplacian(&mesh).unwrap();
    let mass = lumped_mass_matrix(&mesh);
    let x = &pairs.vectors;
    let n = mesh.vertex_count();
    for i in 0..k {
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
            i == 0 || residual <= 1e-10 * scale,
            "pair {i}: residual {residual} of {scale}"
        );
        let m_norm: f64 = (0..n).map(|v| mass[v] * x[(v, i)].powi(2)).sum();
        assert!((m_norm - 1.0).abs() < 1e-9, "pair {i}: xᵀMx = {m_norm}");
    }
}
