//! Watertightness: every edge has exactly two incident faces (closed and edge-manifold), the
//! property behind the WA metric of thesis section 6.5.1.

use crate::TriMesh;
use crate::edge_topology::{EdgeTopology, edge_topology};

/// True when the mesh has at least one edge and every edge has exactly two incident faces.
///
/// ```
/// use meshgnn_geometry::{is_watertight, grid_plane, subdivided_cube};
/// assert!(is_watertight(&subdivided_cube(2)));
/// assert!(!is_watertight(&grid_plane(2, 2)));
/// ```
pub fn is_watertight(mesh: &TriMesh) -> bool {
    watertight_in(&edge_topology(mesh))
}

/// [`is_watertight`] on a precomputed edge table.
pub(crate) fn watertight_in(topology: &EdgeTopology) -> bool {
    topology.edge_count() > 0 && topology.valences().all(|n| n == 2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::icosphere;

    #[test]
    fn sphere_is_watertight_until_a_face_is_removed() {
        let sphere = icosphere(2);
        assert!(is_watertight(&sphere));
        let (v, mut f, ..) = sphere.into_parts();
        f.pop();
        assert!(!is_watertight(&TriMesh::new(v, f).unwrap()));
        assert!(!is_watertight(&TriMesh::default()));
    }
}
