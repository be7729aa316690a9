//! Edge counts behind the WA metric of thesis section 6.5.1: "the percentage of
//! non-watertight edges, which represents the edges with one, three, or more incident faces".

use crate::TriMesh;
use crate::edge_topology::{EdgeTopology, edge_topology};

/// Number of edges with three or more incident faces (non-manifold edges).
///
/// ```
/// use meshgnn_geometry::{TriMesh, non_manifold_edges};
/// let v = vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]];
/// let fin = TriMesh::new(v, vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]])?;
/// assert_eq!(non_manifold_edges(&fin), 1);
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn non_manifold_edges(mesh: &TriMesh) -> usize {
    edge_topology(mesh).valences().filter(|&n| n > 2).count()
}

/// WA (section 6.5.1): `100 × #(edges whose valence ≠ 2) / #edges`, in percent; 0 for a
/// mesh without edges.
///
/// ```
/// use meshgnn_geometry::{non_watertight_edge_percentage, grid_plane, icosphere};
/// assert_eq!(non_watertight_edge_percentage(&icosphere(1)), 0.0);
/// // A 1×1 grid: 5 edges, the 4 sides have one face each.
/// assert_eq!(non_watertight_edge_percentage(&grid_plane(1, 1)), 80.0);
/// ```
pub fn non_watertight_edge_percentage(mesh: &TriMesh) -> f64 {
    non_watertight_percentage_in(&edge_topology(mesh))
}

/// [`non_watertight_edge_percentage`] on a precomputed edge table.
pub(crate) fn non_watertight_percentage_in(topology: &EdgeTopology) -> f64 {
    if topology.edge_count() == 0 {
        return 0.0;
    }
    let bad = topology.valences().filter(|&n| n != 2).count();
    100.0 * bad as f64 / topology.edge_count() as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid_plane;

    #[test]
    fn grid_boundary_fraction_matches_the_count() {
        // n×n grid: 3n² + 2n edges, 4n of them on the boundary.
        let n = 5.0;
        let expected = 100.0 * 4.0 * n / (3.0 * n * n + 2.0 * n);
        let wa = non_watertight_edge_percentage(&grid_plane(5, 5));
        assert!((wa - expected).abs() < 1e-12);
        assert_eq!(non_manifold_edges(&grid_plane(5, 5)), 0);
    }
}
