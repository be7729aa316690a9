//! [`MeshReport`]: every validity figure of a mesh from one pass over its edge table — what
//! `meshsimplify info` prints, and the WA metric of thesis section 6.5.1.

use crate::TriMesh;
use crate::boundary_loops::boundary_loops_in;
use crate::bounding_box::bounding_box;
use crate::connected_components::connected_components;
use crate::degenerate_faces::degenerate_faces;
use crate::duplicate_faces::duplicate_faces;
use crate::edge_topology::edge_topology;
use crate::manifold::{edge_manifold_in, is_vertex_manifold};
use crate::non_manifold_edges::non_watertight_percentage_in;
use crate::watertight::watertight_in;

/// The validity summary of a mesh. Plain data with public fields.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MeshReport {
    /// Number of vertices `#V`.
    pub vertices: usize,
    /// Number of faces `#F`.
    pub faces: usize,
    /// Number of undirected edges `#E` (faces with a repeated index contribute none).
    pub edges: usize,
    /// No edge has more than two faces.
    pub edge_manifold: bool,
    /// The faces around every vertex form a single fan.
    pub vertex_manifold: bool,
    /// Every edge has exactly two faces (and there is at least one edge).
    pub watertight: bool,
    /// Edges with exactly one face.
    pub boundary_edges: usize,
    /// Number of boundary loops (holes and rims).
    pub boundary_loops: usize,
    /// Connected components (vertex-based, see [`crate::connected_components`]).
    pub components: usize,
    /// Faces with a repeated vertex index or zero area.
    pub degenerate_faces: usize,
    /// Faces repeating an earlier face's vertices.
    pub duplicate_faces: usize,
    /// Edges with three or more faces.
    pub non_manifold_edges: usize,
    /// Edges whose two faces run them the same way: an edge-manifold mesh without any is
    /// consistently oriented.
    pub misoriented_edges: usize,
    /// WA (section 6.5.1): percentage of edges whose valence is not 2.
    pub non_manifold_edge_percentage: f64,
    /// Component-wise minimum of the vertex positions (zeros for an empty mesh).
    pub bbox_min: [f32; 3],
    /// Component-wise maximum of the vertex positions (zeros for an empty mesh).
    pub bbox_max: [f32; 3],
}

/// The [`MeshReport`] of `mesh`; the edge table is built once.
///
/// ```
/// use meshgnn_geometry::{mesh_report, grid_plane};
/// let report = mesh_report(&grid_plane(2, 2));
/// assert_eq!((report.edges, report.boundary_edges, report.boundary_loops), (16, 8, 1));
/// assert!(report.edge_manifold && !report.watertight);
/// assert_eq!(report.bbox_max, [1.0, 1.0, 0.0]);
/// ```
pub fn mesh_report(mesh: &TriMesh) -> MeshReport {
    let topology = edge_topology(mesh);
    let (bbox_min, bbox_max) = bounding_box(mesh.vertices()).unwrap_or(([0.0; 3], [0.0; 3]));
    MeshReport {
        vertices: mesh.vertex_count(),
        faces: mesh.face_count(),
        edges: topology.edge_count(),
        edge_manifold: edge_manifold_in(&topology),
        vertex_manifold: is_vertex_manifold(mesh),
        watertight: watertight_in(&topology),
        boundary_edges: topology.valences().filter(|&n| n == 1).count(),
        boundary_loops: boundary_loops_in(&topology).len(),
        components: connected_components(mesh).0,
        degenerate_faces: degenerate_faces(mesh),
        duplicate_faces: duplicate_faces(mesh),
        non_manifold_edges: topology.valences().filter(|&n| n > 2).count(),
        misoriented_edges: (0..topology.edge_count())
            .filter(|&e| matches!(topology.incidences(e), [x, y] if x.from == y.from))
            .count(),
        non_manifold_edge_percentage: non_watertight_percentage_in(&topology),
        bbox_min,
        bbox_max,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::subdivided_cube;

    #[test]
    fn cube_is_closed_watertight_single_component_without_loops() {
        let report = mesh_report(&subdivided_cube(3));
        assert!(report.watertight && report.edge_manifold && report.vertex_manifold);
        assert_eq!(report.components, 1);
        assert_eq!(report.boundary_loops, 0);
        assert_eq!(report.boundary_edges, 0);
        assert_eq!(report.non_manifold_edge_percentage, 0.0);
        assert_eq!(report.misoriented_edges, 0);
        assert_eq!((report.bbox_min, report.bbox_max), ([-1.0; 3], [1.0; 3]));
        assert_eq!(report.vertices + report.faces, report.edges + 2);
    }

    #[test]
    fn broken_mesh_reports_each_problem() {
        let v = vec![
            [0.0; 3],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [5.0, 5.0, 5.0],
        ];
        let f = vec![[0, 1, 2], [1, 0, 3], [0, 1, 4], [2, 1, 0], [5, 5, 0]];
        let report = mesh_report(&TriMesh::new(v, f).unwrap());
        assert!(!report.edge_manifold && !report.watertight);
        assert_eq!(report.non_manifold_edges, 1);
        assert_eq!(report.duplicate_faces, 1);
        assert_eq!(report.degenerate_faces, 1);
        assert_eq!(report.components, 1);
    }

    #[test]
    fn faces_running_an_edge_the_same_way_are_counted() {
        let v = vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0]];
        let consistent = TriMesh::new(v.clone(), vec![[0, 1, 2], [1, 0, 3]]).unwrap();
        assert_eq!(mesh_report(&consistent).misoriented_edges, 0);
        let flipped = TriMesh::new(v, vec![[0, 1, 2], [0, 1, 3]]).unwrap();
        let report = mesh_report(&flipped);
        assert_eq!(report.misoriented_edges, 1);
        assert!(report.edge_manifold);
    }
}
