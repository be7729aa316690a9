//! Graph Laplacians of an unweighted undirected graph, thesis eq. 2.13-2.14: the
//! combinatorial `L = D − A` and the normalised `L = I − D^{-1/2} A D^{-1/2}`.
//!
//! # Conventions
//! - Positive semi-definite: `L = D − A` (eq. 2.13 with unit weights); `L·1 = 0`.
//! - The input is an undirected edge list `edges: #E×2` over `vertex_count` vertices; each
//!   pair is one undirected edge in either direction. Repeated edges count once (the graph is
//!   unweighted) and self-loops are ignored (they cancel in `D − A`).
//! - Normalised Laplacian: an isolated vertex (degree 0) has an all-zero row and column, so
//!   the spectrum stays in `[0, 2]` (the convention of networkx).
//! - Matrices are `faer::sparse::SparseColMat<usize, f64>`, symmetric, with both triangles and
//!   the diagonal stored.

use faer::sparse::{SparseColMat, Triplet};

use crate::TriMesh;
use crate::edge_topology::edge_topology;
use crate::error::{Error, Result};

/// Eq. 2.13 with unit weights: the combinatorial Laplacian `D − A`, `#V×#V`.
///
/// ```
/// use meshgnn_geometry::combinatorial_laplacian;
/// let l = combinatorial_laplacian(3, &[[0, 1], [1, 2]])?.to_dense();
/// assert_eq!((l[(0, 0)], l[(1, 1)], l[(0, 1)], l[(0, 2)]), (1.0, 2.0, -1.0, 0.0));
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn combinatorial_laplacian(
    vertex_count: usize,
    edges: &[[u32; 2]],
) -> Result<SparseColMat<usize, f64>> {
    let (unique, degree) = unique_edges(vertex_count, edges)?;
    assemble(vertex_count, &unique, |_, _| -1.0, |v| degree[v] as f64)
}

/// Eq. 2.14: the normalised Laplacian `I − D^{-1/2} A D^{-1/2}`, `#V×#V` (zero rows for
/// isolated vertices).
///
/// ```
/// use meshgnn_geometry::normalized_laplacian;
/// let l = normalized_laplacian(3, &[[0, 1], [1, 2]])?.to_dense();
/// assert_eq!(l[(1, 1)], 1.0);
/// assert!((l[(0, 1)] + 1.0 / 2f64.sqrt()).abs() < 1e-15);
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn normalized_laplacian(
    vertex_count: usize,
    edges: &[[u32; 2]],
) -> Result<SparseColMat<usize, f64>> {
    let (unique, degree) = unique_edges(vertex_count, edges)?;
    let inv_sqrt: Vec<f64> = degree
        .iter()
        .map(|&d| if d > 0 { 1.0 / (d as f64).sqrt() } else { 0.0 })
        .collect();
    assemble(
        vertex_count,
        &unique,
        |a, b| -inv_sqrt[a] * inv_sqrt[b],
        |v| if degree[v] > 0 { 1.0 } else { 0.0 },
    )
}

/// [`combinatorial_laplacian`] of a mesh's edge graph.
///
/// ```
/// use meshgnn_geometry::{combinatorial_laplacian_of_mesh, icosphere};
/// let l = combinatorial_laplacian_of_mesh(&icosphere(0))?;
/// assert_eq!(l.to_dense()[(0, 0)], 5.0);
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn combinatorial_laplacian_of_mesh(mesh: &TriMesh) -> Result<SparseColMat<usize, f64>> {
    combinatorial_laplacian(mesh.vertex_count(), edge_topology(mesh).edges())
}

/// [`normalized_laplacian`] of a mesh's edge graph.
///
/// ```
/// use meshgnn_geometry::{normalized_laplacian_of_mesh, icosphere};
/// let l = normalized_laplacian_of_mesh(&icosphere(0))?;
/// assert!((l.to_dense()[(0, 11)] + 0.2).abs() < 1e-15);
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn normalized_laplacian_of_mesh(mesh: &TriMesh) -> Result<SparseColMat<usize, f64>> {
    normalized_laplacian(mesh.vertex_count(), edge_topology(mesh).edges())
}

/// Sorted, de-duplicated `a < b` edges without self-loops, and the vertex degrees.
fn unique_edges(vertex_count: usize, edges: &[[u32; 2]]) -> Result<(Vec<[u32; 2]>, Vec<u32>)> {
    let mut unique = Vec::with_capacity(edges.len());
    for (index, &[a, b]) in edges.iter().enumerate() {
        if let Some(&value) = [a, b].iter().find(|&&v| v as usize >= vertex_count) {
            return Err(Error::IndexOutOfRange {
                element: "edge",
                index,
                target: "vertex",
                value: u64::from(value),
                count: vertex_count,
            });
        }
        if a != b {
            unique.push([a.min(b), a.max(b)]);
        }
    }
    unique.sort_unstable();
    unique.dedup();
    let mut degree = vec![0u32; vertex_count];
    for &[a, b] in &unique {
        degree[a as usize] += 1;
        degree[b as usize] += 1;
    }
    Ok((unique, degree))
}

/// A symmetric sparse matrix with `off(a, b)` at both `(a, b)` and `(b, a)` for each edge and
/// `diagonal(v)` on the diagonal.
pub(crate) fn assemble(
    vertex_count: usize,
    edges: &[[u32; 2]],
    off: impl Fn(usize, usize) -> f64,
    diagonal: impl Fn(usize) -> f64,
) -> Result<SparseColMat<usize, f64>> {
    let mut triplets = Vec::with_capacity(2 * edges.len() + vertex_count);
    for &[a, b] in edges {
        let (a, b) = (a as usize, b as usize);
        let w = off(a, b);
        triplets.push(Triplet::new(a, b, w));
        triplets.push(Triplet::new(b, a, w));
    }
    triplets.extend((0..vertex_count).map(|v| Triplet::new(v, v, diagonal(v))));
    SparseColMat::try_new_from_triplets(vertex_count, vertex_count, &triplets).map_err(|e| {
        Error::Solver {
            solver: "sparse matrix assembly",
            message: format!("{e:?}"),
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::Side;
    use std::f64::consts::PI;

    fn spectrum(l: &SparseColMat<usize, f64>) -> Vec<f64> {
        l.to_dense().self_adjoint_eigenvalues(Side::Lower).unwrap()
    }

    fn assert_close(actual: &[f64], mut expected: Vec<f64>) {
        expected.sort_by(f64::total_cmp);
        assert_eq!(actual.len(), expected.len());
        for (a, e) in actual.iter().zip(&expected) {
            assert!((a - e).abs() < 1e-10, "{a} vs {e}");
        }
    }

    #[test]
    fn path_and_cycle_spectra_in_closed_form() {
        let n = 9u32;
        let path: Vec<[u32; 2]> = (0..n - 1).map(|i| [i, i + 1]).collect();
        let expected = (0..n).map(|k| 2.0 - 2.0 * (PI * f64::from(k) / f64::from(n)).cos());
        assert_close(
            &spectrum(&combinatorial_laplacian(n as usize, &path).unwrap()),
            expected.collect(),
        );
        // Both directions and a repeat: still the same graph.
        let cycle: Vec<[u32; 2]> = (0..n).map(|i| [(i + 1) % n, i]).chain([[0, 1]]).collect();
        let expected = (0..n).map(|k| 2.0 - 2.0 * (2.0 * PI * f64::from(k) / f64::from(n)).cos());
        let l = combinatorial_laplacian(n as usize, &cycle).unwrap();
        assert_close(&spectrum(&l), expected.clone().collect());
        // The cycle is 2-regular: normalised = L / 2.
        let normalized = normalized_laplacian(n as usize, &cycle).unwrap();
        assert_close(&spectrum(&normalized), expected.map(|x| x / 2.0).collect());
    }

    #[test]
    fn rows_sum_to_zero_and_isolated_vertices_are_zero() {
        let l = combinatorial_laplacian(5, &[[0, 1], [1, 2], [2, 0], [3, 3]])
            .unwrap()
            .to_dense();
        for r in 0..5 {
            assert_eq!((0..5).map(|c| l[(r, c)]).sum::<f64>(), 0.0);
        }
        let n = normalized_laplacian(5, &[[0, 1]]).unwrap().to_dense();
        assert_eq!((n[(4, 4)], n[(0, 0)]), (0.0, 1.0));
        assert!(matches!(
            combinatorial_laplacian(2, &[[0, 2]]),
            Err(Error::IndexOutOfRange {
                element: "edge",
                index: 0,
                value: 2,
                ..
            })
        ));
    }
}
