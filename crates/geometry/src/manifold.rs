//! Manifoldness checks: edge-manifold (every edge has at most two faces) and vertex-manifold
//! (the faces around every vertex form a single fan, open or closed).
//!
//! A mesh that fails them breaks half-edge structures, QEM decimation and the spiral
//! sequences of thesis eq. 2.27-2.29. Faces with a repeated vertex index are ignored, as in
//! [`crate::edge_topology`].

use rayon::prelude::*;

use crate::TriMesh;
use crate::edge_topology::{EdgeTopology, edge_topology};

/// True when no edge has more than two incident faces.
///
/// ```
/// use meshgnn_geometry::{TriMesh, is_edge_manifold};
/// let v = vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]];
/// let fin = TriMesh::new(v, vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]])?;
/// assert!(!is_edge_manifold(&fin));
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn is_edge_manifold(mesh: &TriMesh) -> bool {
    edge_manifold_in(&edge_topology(mesh))
}

/// [`is_edge_manifold`] on a precomputed edge table.
pub(crate) fn edge_manifold_in(topology: &EdgeTopology) -> bool {
    topology.valences().all(|n| n <= 2)
}

/// The vertices whose incident faces form more than one edge-connected fan (e.g. the shared
/// tip of two cones, a "bowtie"), ascending.
///
/// ```
/// use meshgnn_geometry::{TriMesh, non_manifold_vertices};
/// let v = vec![[0.0; 3], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [-1.0, -1.0, 0.0]];
/// let bowtie = TriMesh::new(v, vec![[0, 1, 2], [0, 3, 4]])?;
/// assert_eq!(non_manifold_vertices(&bowtie), vec![0]);
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn non_manifold_vertices(mesh: &TriMesh) -> Vec<u32> {
    let (offsets, corners) = vertex_corners(mesh);
    let triangles = mesh.triangles();
    (0..mesh.vertex_count())
        .into_par_iter()
        .filter(|&v| {
            let corner_range = offsets[v]..offsets[v + 1];
            fan_count(v as u32, &corners[corner_range], triangles) > 1
        })
        .map(|v| v as u32)
        .collect()
}

/// True when every vertex's faces form a single fan (see [`non_manifold_vertices`]).
pub fn is_vertex_manifold(mesh: &TriMesh) -> bool {
    non_manifold_vertices(mesh).is_empty()
}

/// Vertex → incident faces in CSR layout (`offsets: #V+1`, faces ascending), skipping faces
/// with a repeated vertex index. Built by a counting sort, O(V + F).
pub(crate) fn vertex_corners(mesh: &TriMesh) -> (Vec<usize>, Vec<u32>) {
    let valid = |t: &[u32; 3]| t[0] != t[1] && t[1] != t[2] && t[0] != t[2];
    let mut offsets = vec![0usize; mesh.vertex_count() + 1];
    for t in mesh.triangles().iter().filter(|t| valid(t)) {
        for &v in t {
            offsets[v as usize + 1] += 1;
        }
    }
    for i in 0..mesh.vertex_count() {
        offsets[i + 1] += offsets[i];
    }
    let mut next = offsets.clone();
    let mut faces = vec![0u32; offsets[mesh.vertex_count()]];
    for (f, t) in mesh
        .triangles()
        .iter()
        .enumerate()
        .filter(|(_, t)| valid(t))
    {
        for &v in t {
            faces[next[v as usize]] = f as u32;
            next[v as usize] += 1;
        }
    }
    (offsets, faces)
}

/// Number of fans around `vertex`: its faces, joined when they share an edge `(vertex, w)`.
fn fan_count(vertex: u32, faces: &[u32], triangles: &[[u32; 3]]) -> usize {
    if faces.len() <= 1 {
        return faces.len();
    }
    // (opposite vertex w, local face index) for both edges of each face at `vertex`.
    let mut spokes: Vec<(u32, usize)> = Vec::with_capacity(2 * faces.len());
    for (local, &f) in faces.iter().enumerate() {
        for w in triangles[f as usize] {
            if w != vertex {
                spokes.push((w, local));
            }
        }
    }
    spokes.sort_unstable();
    let mut parent: Vec<usize> = (0..faces.len()).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let mut fans = faces.len();
    for pair in spokes.windows(2) {
        if pair[0].0 == pair[1].0 {
            let (a, b) = (root(&mut parent, pair[0].1), root(&mut parent, pair[1].1));
            if a != b {
                parent[a] = b;
                fans -= 1;
            }
        }
    }
    fans
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{grid_plane, icosphere, subdivided_cube};

    #[test]
    fn analytic_shapes_are_manifold() {
        for mesh in [icosphere(2), subdivided_cube(2), grid_plane(4, 3)] {
            assert!(is_edge_manifold(&mesh));
            assert!(is_vertex_manifold(&mesh));
        }
    }

    #[test]
    fn three_faces_on_one_edge_are_not_edge_manifold_but_two_are() {
        let v = vec![
            [0.0; 3],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        let two = TriMesh::new(v.clone(), vec![[0, 1, 2], [1, 0, 3]]).unwrap();
        assert!(is_edge_manifold(&two));
        let three = TriMesh::new(v, vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]]).unwrap();
        assert!(!is_edge_manifold(&three));
    }

    #[test]
    fn two_cones_sharing_a_tip_are_not_vertex_manifold() {
        // Two closed fans of 4 faces around vertex 0 that share only vertex 0.
        let mut v = vec![[0.0f32; 3]];
        let mut faces = Vec::new();
        for side in [1.0f32, -1.0] {
            let base = v.len() as u32;
            for k in 0..4 {
                let a = k as f32 * std::f32::consts::FRAC_PI_2;
                v.push([a.cos(), a.sin(), side]);
            }
            for k in 0..4 {
                faces.push([0, base + k, base + (k + 1) % 4]);
            }
        }
        let mesh = TriMesh::new(v, faces).unwrap();
        assert_eq!(non_manifold_vertices(&mesh), vec![0]);
        assert!(is_edge_manifold(&mesh));
    }
}
