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

/// True when some vertex of `faces` has more than one fan (see [`non_manifold_vertices`]):
/// the same test on a few faces of a larger mesh, without a vertex table of its size.
pub(crate) fn has_pinched_vertex(faces: &[[u32; 3]]) -> bool {
    let mut corners: Vec<(u32, u32)> = faces
        .iter()
        .enumerate()
        .filter(|(_, t)| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .flat_map(|(f, t)| t.map(|v| (v, f as u32)))
        .collect();
    corners.sort_unstable();
    corners.chunk_by(|a, b| a.0 == b.0).any(|around| {
        let fan: Vec<u32> = around.iter().map(|&(_, f)| f).collect();
        fan_count(around[0].0, &fan, faces) > 1
    })
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
    fan_forest(vertex, faces, triangles).1
}

/// The fan of each of `faces` around `vertex` (a label per face, equal within a fan) and the
/// number of fans (see [`fan_count`]).
pub(crate) fn fans_around(
    vertex: u32,
    faces: &[u32],
    triangles: &[[u32; 3]],
) -> (Vec<usize>, usize) {
    let (mut parent, fans) = fan_forest(vertex, faces, triangles);
    let labels = (0..faces.len()).map(|i| root(&mut parent, i)).collect();
    (labels, fans)
}

/// A union-find forest over `faces` (local indices) joining faces that share an edge
/// `(vertex, w)`, and its number of trees.
fn fan_forest(vertex: u32, faces: &[u32], triangles: &[[u32; 3]]) -> (Vec<usize>, usize) {
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
    (parent, fans)
}

fn root(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{grid_plane, icosphere, subdivided_cube};

    #[test]
    fn pinches_among_a_few_faces_are_found_as_in_a_whole_mesh() {
        let sphere = icosphere(1);
        assert!(!has_pinched_vertex(sphere.triangles()));
        // Two faces of the sphere that share only a vertex: a bowtie.
        let faces = sphere.triangles();
        let (a, b) = faces
            .iter()
            .enumerate()
            .flat_map(|(i, s)| faces[i + 1..].iter().map(move |t| (s, t)))
            .find(|(s, t)| s.iter().filter(|v| t.contains(v)).count() == 1)
            .unwrap();
        assert!(has_pinched_vertex(&[*a, *b]));
        // The same two faces with a degenerate face between them: still a bowtie.
        let shared = *a.iter().find(|v| b.contains(v)).unwrap();
        assert!(has_pinched_vertex(&[*a, [shared, shared, a[0]], *b]));
        assert!(!has_pinched_vertex(&[]));
    }

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
