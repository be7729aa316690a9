//! The undirected edge → incident faces table, computed once and shared by the validity
//! checks ([`crate::mesh_report`], manifold and watertight tests, boundary loops, WA of thesis
//! section 6.5.1).
//!
//! Built by sorting the `3·#F` half-edges by their undirected key (a parallel unstable sort of
//! plain integers, no hashing): O(F log F), about 3 × 12 bytes per face.
//!
//! # Conventions
//! - An edge is `[a, b]` with `a < b`; edges are sorted lexicographically.
//! - Faces with a repeated vertex index have no well-defined edges and are skipped (count them
//!   with [`crate::degenerate_faces`]); zero-area faces with three distinct indices are kept.

use rayon::prelude::*;

use crate::TriMesh;

/// One face incident to an edge, with the edge's direction inside that face
/// (`from → to` follows the face's counter-clockwise order).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EdgeIncidence {
    /// The incident face.
    pub face: u32,
    /// First vertex of the edge in the face's winding order.
    pub from: u32,
    /// Second vertex of the edge in the face's winding order.
    pub to: u32,
}

/// Every undirected edge of a mesh with the faces around it, in CSR layout.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct EdgeTopology {
    edges: Vec<[u32; 2]>,
    offsets: Vec<usize>,
    incidences: Vec<EdgeIncidence>,
}

impl EdgeTopology {
    /// The undirected edges `#E×2`, `a < b`, sorted.
    pub fn edges(&self) -> &[[u32; 2]] {
        &self.edges
    }

    /// Number of undirected edges `#E`.
    pub fn edge_count(&self) -> usize {
        self.edges.len()
    }

    /// The faces incident to edge `edge` (empty when `edge >= #E`).
    pub fn incidences(&self, edge: usize) -> &[EdgeIncidence] {
        match (self.offsets.get(edge), self.offsets.get(edge + 1)) {
            (Some(&start), Some(&end)) => self.incidences.get(start..end).unwrap_or(&[]),
            _ => &[],
        }
    }

    /// Number of faces incident to edge `edge` (its valence; 0 when out of range).
    pub fn valence(&self, edge: usize) -> usize {
        self.incidences(edge).len()
    }

    /// Per-edge valences, `#E`.
    pub fn valences(&self) -> impl Iterator<Item = usize> + '_ {
        self.offsets.windows(2).map(|w| w[1] - w[0])
    }
}

/// The edge table of `mesh` (see the module conventions).
///
/// ```
/// use meshgnn_geometry::{TriMesh, edge_topology};
/// let v = vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
/// let mesh = TriMesh::new(v, vec![[0, 1, 2], [1, 3, 2]])?;
/// let topology = edge_topology(&mesh);
/// assert_eq!(topology.edges(), &[[0, 1], [0, 2], [1, 2], [1, 3], [2, 3]]);
/// assert_eq!(topology.valences().collect::<Vec<_>>(), vec![1, 1, 2, 1, 1]);
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn edge_topology(mesh: &TriMesh) -> EdgeTopology {
    // Half-edge record packed into one u128: key (a << 32 | b) in the high 64 bits, then the
    // face and the local corner, so sorting the integers groups edges deterministically.
    let mut half_edges: Vec<u128> = mesh
        .triangles()
        .par_iter()
        .enumerate()
        .filter(|(_, t)| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .flat_map_iter(|(f, t)| {
            (0..3u32).map(move |corner| {
                let (from, to) = (t[corner as usize], t[(corner as usize + 1) % 3]);
                let key = (u64::from(from.min(to)) << 32) | u64::from(from.max(to));
                (u128::from(key) << 64) | ((f as u128) << 2) | u128::from(corner)
            })
        })
        .collect();
    half_edges.par_sort_unstable();
    let triangles = mesh.triangles();
    let mut edges = Vec::with_capacity(half_edges.len() / 2 + 1);
    let mut offsets = Vec::with_capacity(half_edges.len() / 2 + 2);
    let mut incidences = Vec::with_capacity(half_edges.len());
    let mut previous_key = None;
    for record in half_edges {
        let key = (record >> 64) as u64;
        if previous_key != Some(key) {
            previous_key = Some(key);
            edges.push([(key >> 32) as u32, key as u32]);
            offsets.push(incidences.len());
        }
        let face = ((record >> 2) & 0xFFFF_FFFF) as u32;
        let corner = (record & 3) as usize;
        let t = triangles[face as usize];
        incidences.push(EdgeIncidence {
            face,
            from: t[corner],
            to: t[(corner + 1) % 3],
        });
    }
    offsets.push(incidences.len());
    EdgeTopology {
        edges,
        offsets,
        incidences,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{icosphere, subdivided_cube};

    #[test]
    fn closed_meshes_satisfy_euler_and_two_faces_per_edge() {
        for mesh in [icosphere(3), subdivided_cube(3)] {
            let topology = edge_topology(&mesh);
            let (v, e, f) = (
                mesh.vertex_count(),
                topology.edge_count(),
                mesh.face_count(),
            );
            assert_eq!(v as i64 - e as i64 + f as i64, 2);
            assert!(topology.valences().all(|n| n == 2));
            // The two faces traverse a manifold edge in opposite directions.
            for edge in 0..e {
                let [a, b] = topology.incidences(edge) else {
                    panic!("edge {edge}")
                };
                assert_eq!((a.from, a.to), (b.to, b.from));
            }
        }
    }

    #[test]
    fn faces_with_repeated_vertices_are_skipped_and_out_of_range_is_empty() {
        let v = vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let mesh = TriMesh::new(v, vec![[0, 0, 1], [0, 1, 2]]).unwrap();
        let topology = edge_topology(&mesh);
        assert_eq!(topology.edge_count(), 3);
        assert!(topology.incidences(3).is_empty());
        assert_eq!(topology.incidences(0)[0].face, 1);
    }
}
