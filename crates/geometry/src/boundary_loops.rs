//! Ordered boundary loops: the chains of edges that have exactly one incident face.
//! Holes in a scan, the rim of an open surface, and cracks in a simplified mesh show up here.

use crate::TriMesh;
use crate::edge_topology::{EdgeTopology, edge_topology};

/// The boundary loops of `mesh`, each an ordered list of vertex indices (the closing edge from
/// the last back to the first vertex is implied).
///
/// A loop follows the winding of its faces (`from → to` as the edge appears in its face) where
/// the orientation is consistent, and starts at the smallest vertex index of the first unused
/// boundary edge in sorted order; loops are listed in that order. Where the boundary passes
/// through a vertex several times (a non-manifold vertex) the walk takes the edges in sorted
/// order, and a chain that cannot close (possible only on non-manifold input) is returned open.
///
/// ```
/// use meshgnn_geometry::{boundary_loops, grid_plane, icosphere};
/// assert_eq!(boundary_loops(&grid_plane(2, 1)), vec![vec![0, 1, 2, 5, 4, 3]]);
/// assert!(boundary_loops(&icosphere(1)).is_empty());
/// ```
pub fn boundary_loops(mesh: &TriMesh) -> Vec<Vec<u32>> {
    boundary_loops_in(&edge_topology(mesh))
}

/// [`boundary_loops`] on a precomputed edge table.
pub(crate) fn boundary_loops_in(topology: &EdgeTopology) -> Vec<Vec<u32>> {
    // Boundary edges directed as in their face.
    let boundary: Vec<[u32; 2]> = (0..topology.edge_count())
        .filter_map(|e| match topology.incidences(e) {
            [only] => Some([only.from, only.to]),
            _ => None,
        })
        .collect();
    // Vertex → boundary edges, sorted by (vertex, edge).
    let mut at_vertex: Vec<(u32, usize)> = boundary
        .iter()
        .enumerate()
        .flat_map(|(e, &[a, b])| [(a, e), (b, e)])
        .collect();
    at_vertex.sort_unstable();
    let edges_at = |v: u32| {
        let start = at_vertex.partition_point(|&(w, _)| w < v);
        let end = at_vertex.partition_point(|&(w, _)| w <= v);
        &at_vertex[start..end]
    };
    let mut used = vec![false; boundary.len()];
    let mut loops = Vec::new();
    for first in 0..boundary.len() {
        if used[first] {
            continue;
        }
        used[first] = true;
        let [start, mut current] = boundary[first];
        let mut chain = vec![start];
        while current != start {
            chain.push(current);
            // Prefer an unused edge leaving `current` in face order, then any unused one.
            let candidates = edges_at(current);
            let next = candidates
                .iter()
                .find(|&&(_, e)| !used[e] && boundary[e][0] == current)
                .or_else(|| candidates.iter().find(|&&(_, e)| !used[e]));
            let Some(&(_, e)) = next else { break };
            used[e] = true;
            let [a, b] = boundary[e];
            current = if a == current { b } else { a };
        }
        loops.push(chain);
    }
    loops
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{grid_plane, subdivided_cube};

    #[test]
    fn grid_has_one_loop_through_every_boundary_vertex_counter_clockwise() {
        let (nx, ny) = (4u32, 3u32);
        let loops = boundary_loops(&grid_plane(nx, ny));
        assert_eq!(loops.len(), 1);
        let ring = &loops[0];
        assert_eq!(ring.len(), 2 * (nx + ny) as usize);
        // Consecutive vertices are grid neighbours, and the walk is counter-clockwise seen
        // from +z (positive signed area), as the faces are.
        let plane = grid_plane(nx, ny);
        let p = |v: u32| plane.vertices()[v as usize];
        let mut area = 0.0f64;
        for i in 0..ring.len() {
            let (a, b) = (p(ring[i]), p(ring[(i + 1) % ring.len()]));
            area += f64::from(a[0] * b[1] - a[1] * b[0]) / 2.0;
        }
        assert!((area - 1.0).abs() < 1e-6, "{area}");
    }

    #[test]
    fn cube_with_two_holes_has_two_loops() {
        let (v, f, ..) = subdivided_cube(3).into_parts();
        // Remove the first face and one far away (different cube sides): two triangular holes.
        let f: Vec<_> = f
            .iter()
            .enumerate()
            .filter(|&(i, _)| i != 0 && i != 60)
            .map(|(_, t)| *t)
            .collect();
        let loops = boundary_loops(&TriMesh::new(v, f).unwrap());
        assert_eq!(loops.iter().map(Vec::len).collect::<Vec<_>>(), vec![3, 3]);
        assert!(boundary_loops(&subdivided_cube(3)).is_empty());
    }
}
