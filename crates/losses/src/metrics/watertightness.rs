//! Watertightness WA (thesis ch. 6.5.1): the percentage of edges that are not watertight.

use meshgnn_geometry::{TriMesh, mesh_report};

/// WA: percentage (0-100) of the undirected edges of `mesh` with one, three or more incident
/// faces — edges around holes and non-manifold edges. 0 for a closed 2-manifold; 0 for a mesh
/// without edges. Counted by the geometry crate's `mesh_report` from its edge table.
///
/// ```
/// use meshgnn_geometry::{grid_plane, icosphere};
/// use meshgnn_losses::metrics::watertightness;
/// assert_eq!(watertightness(&icosphere(1)), 0.0);
/// assert_eq!(watertightness(&grid_plane(2, 2)), 50.0); // 8 boundary edges of 16
/// ```
pub fn watertightness(mesh: &TriMesh) -> f64 {
    mesh_report(mesh).non_manifold_edge_percentage
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshgnn_geometry::icosphere;

    #[test]
    fn one_missing_face_opens_three_edges() {
        let sphere = icosphere(1); // 80 faces, 120 edges
        let (v, mut t, ..) = sphere.into_parts();
        t.pop();
        let open = TriMesh::new(v, t).unwrap();
        assert!((watertightness(&open) - 300.0 / 120.0).abs() < 1e-12);
    }

    #[test]
    fn fin_edge_counts() {
        let v = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, -1.0, 0.0],
        ];
        // Three faces on edge (0,1): valence 3; the six other edges have valence 1.
        let fin = TriMesh::new(v, vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]]).unwrap();
        assert_eq!(watertightness(&fin), 100.0);
    }
}
