//! Mesh connectivity as sparse matrices: the vertex–vertex adjacency `A` every mesh GNN
//! aggregates over (thesis eq. 2.2 neighbourhoods, eq. 6.1 DevConv, eq. 6.3 `A_s = SᵀAS`) and
//! the vertex–face incidence. The undirected edge list with the faces on each edge is
//! [`meshgnn_geometry::edge_topology`], which these are built from.
//!
//! # Conventions
//! - Adjacency matrices are symmetric `#V×#V` [`CsrMatrix`]es with value 1 per edge, no
//!   self-loops, neighbours sorted by index within each row. Faces with a repeated vertex
//!   contribute no edges; unreferenced vertices have empty rows.
//! - Incidence is `#V×#F` with value 1 where the vertex is a corner of the face.

use meshgnn_geometry::{TriMesh, edge_topology};
use rayon::prelude::*;

use crate::{CsrMatrix, Error, Result};

/// The symmetric adjacency `#n×#n` of undirected `edges: #E×2` (either direction, duplicates
/// and self-loops dropped): the graph of a point cloud's k-NN edges joined with a mesh's,
/// as the edge predictor of ch. 6.3 builds it. O(E log E).
///
/// ```
/// use meshgnn_graph::adjacency_from_edges;
/// let a = adjacency_from_edges(3, &[[0, 1], [1, 0], [2, 1], [2, 2]])?;
/// assert_eq!(a.row_offsets(), &[0, 1, 3, 4]);
/// assert_eq!(a.col_indices(), &[1, 0, 2, 1]);
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn adjacency_from_edges(n: usize, edges: &[[u32; 2]]) -> Result<CsrMatrix> {
    if let Some(&[a, b]) = edges
        .iter()
        .find(|e| e[0] as usize >= n || e[1] as usize >= n)
    {
        return Err(Error::IndexOutOfRange {
            what: "edge endpoint",
            index: a.max(b) as usize,
            len: n,
        });
    }
    let mut keys: Vec<u64> = edges
        .iter()
        .filter(|e| e[0] != e[1])
        .flat_map(|&[a, b]| {
            [
                (u64::from(a) << 32) | u64::from(b),
                (u64::from(b) << 32) | u64::from(a),
            ]
        })
        .collect();
    keys.par_sort_unstable();
    keys.dedup();
    let mut row_offsets = vec![0usize; n + 1];
    for &key in &keys {
        row_offsets[(key >> 32) as usize + 1] += 1;
    }
    for r in 0..n {
        row_offsets[r + 1] += row_offsets[r];
    }
    let col_indices: Vec<u32> = keys.iter().map(|&key| key as u32).collect();
    let values = vec![1.0; col_indices.len()];
    CsrMatrix::from_parts(n, n, row_offsets, col_indices, values)
}

/// The vertex–vertex adjacency `#V×#V` of `mesh` (see the module conventions). O(F log F).
///
/// ```
/// let a = meshgnn_graph::vertex_adjacency(&meshgnn_geometry::icosphere(0))?;
/// assert_eq!(a.nnz(), 60); // 30 edges, both directions
/// assert!(a.row_sums().iter().all(|&d| d == 5.0)); // valence 5 everywhere
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn vertex_adjacency(mesh: &TriMesh) -> Result<CsrMatrix> {
    adjacency_from_edges(mesh.vertex_count(), edge_topology(mesh).edges())
}

/// The vertex–face incidence `#V×#F` of `mesh`: row `v` lists the faces with `v` as a corner,
/// in increasing order. O(F + V).
///
/// ```
/// use meshgnn_geometry::grid_plane;
/// let inc = meshgnn_graph::vertex_face_incidence(&grid_plane(1, 1))?;
/// // Faces [0, 1, 3] and [0, 3, 2]: vertices 0 and 3 (the diagonal) touch both.
/// assert_eq!(inc.row_sums(), vec![2.0, 1.0, 1.0, 2.0]);
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn vertex_face_incidence(mesh: &TriMesh) -> Result<CsrMatrix> {
    let n = mesh.vertex_count();
    let mut row_offsets = vec![0usize; n + 1];
    for t in mesh.triangles() {
        for (c, &v) in t.iter().enumerate() {
            // A corner repeated in one face counts once.
            if !t[..c].contains(&v) {
                row_offsets[v as usize + 1] += 1;
            }
        }
    }
    for r in 0..n {
        row_offsets[r + 1] += row_offsets[r];
    }
    let mut next = row_offsets.clone();
    let mut col_indices = vec![0u32; row_offsets[n]];
    // Faces visited in increasing order, so each row comes out sorted.
    for (f, t) in mesh.triangles().iter().enumerate() {
        for (c, &v) in t.iter().enumerate() {
            if !t[..c].contains(&v) {
                col_indices[next[v as usize]] = f as u32;
                next[v as usize] += 1;
            }
        }
    }
    let values = vec![1.0; col_indices.len()];
    CsrMatrix::from_parts(n, mesh.face_count(), row_offsets, col_indices, values)
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshgnn_geometry::{grid_plane, subdivided_cube};

    #[test]
    fn grid_adjacency_is_symmetric_with_known_valences() {
        let mesh = grid_plane(4, 4);
        let a = vertex_adjacency(&mesh).unwrap();
        assert_eq!(a, a.transpose());
        // Interior vertex 6 = (1, 1): W, E, S, N and the diagonal (0, 0)-(2, 2) (cells split a→c).
        assert_eq!(a.row(6).0, &[0, 1, 5, 7, 11, 12]);
        // Corner 0: 1, 5, 6.
        assert_eq!(a.row(0).0, &[1, 5, 6]);
        let edges: usize = a.nnz() / 2;
        assert_eq!(edges, 4 * 5 * 2 + 16); // horizontal + vertical + diagonals
    }

    #[test]
    fn euler_characteristic_of_closed_cube() {
        let mesh = subdivided_cube(3);
        let a = vertex_adjacency(&mesh).unwrap();
        let (v, e, f) = (
            mesh.vertex_count() as i64,
            a.nnz() as i64 / 2,
            mesh.face_count() as i64,
        );
        assert_eq!(v - e + f, 2);
        let inc = vertex_face_incidence(&mesh).unwrap();
        assert_eq!(inc.nnz(), 3 * mesh.face_count());
        assert_eq!(inc.transpose().row_sums(), vec![3.0; mesh.face_count()]);
    }

    #[test]
    fn out_of_range_edge_is_an_error() {
        assert!(matches!(
            adjacency_from_edges(2, &[[0, 2]]),
            Err(Error::IndexOutOfRange { index: 2, .. })
        ));
    }
}
