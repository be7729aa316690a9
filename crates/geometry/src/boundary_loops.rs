//! Ordered boundary loops: the chains of edges that have exactly one incident face.
//! Holes in a scan, the rim of an open surface, and cracks in a simplified mesh show up here.

use std::collections::{HashMap, HashSet};

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

/// For each of `vertices`, whether it ends a border edge of `mesh` (an edge of one face): one
/// pass over the faces counting only the edges at those vertices, O(F + n) whatever the
/// boundary's size. Faces with a repeated corner are skipped, as in [`boundary_loops`].
///
/// ```
/// use meshgnn_geometry::{grid_plane, on_border};
/// // The 2 × 2 grid: its middle vertex 4 is inside, its corner 0 on the border.
/// assert_eq!(on_border(&grid_plane(2, 2), &[4, 0]), vec![false, true]);
/// ```
pub fn on_border(mesh: &TriMesh, vertices: &[u32]) -> Vec<bool> {
    let asked: HashSet<u32> = vertices.iter().copied().collect();
    let mut uses: HashMap<(u32, u32), u32> = HashMap::new();
    for &[a, b, c] in mesh.triangles() {
        if a == b || b == c || a == c {
            continue;
        }
        for (x, y) in [(a, b), (b, c), (c, a)] {
            if asked.contains(&x) || asked.contains(&y) {
                *uses.entry((x.min(y), x.max(y))).or_default() += 1;
            }
        }
    }
    let border: HashSet<u32> = uses
        .into_iter()
        .filter(|&(_, n)| n == 1)
        .flat_map(|((x, y), _)| [x, y])
        .collect();
    vertices.iter().map(|v| border.contains(v)).collect()
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
    fn border_vertices_of_a_cube_with_a_hole_are_the_hole_corners() {
        let (v, f, ..) = subdivided_cube(3).into_parts();
        let hole = f[0];
        let open = TriMesh::new(v, f[1..].to_vec()).unwrap();
        let all: Vec<u32> = (0..open.vertex_count() as u32).collect();
        let flags = on_border(&open, &all);
        let expected: Vec<bool> = all.iter().map(|v| hole.contains(v)).collect();
        assert_eq!(flags, expected);
        // An edge of three faces is not a border; a repeated corner makes no edge.
        let fan = TriMesh::new(
            vec![[0.0; 3]; 5],
            vec![[0, 1, 2], [0, 1, 3], [0, 1, 4], [2, 2, 3]],
        )
        .unwrap();
        assert_eq!(on_border(&fan, &[0, 1, 2]), vec![true, true, true]);
        assert_eq!(on_border(&fan, &[]), Vec::<bool>::new());
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
