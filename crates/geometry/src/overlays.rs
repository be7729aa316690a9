//! Overlays: a lone face or a pair of faces that shares no edge with the rest of a mesh while
//! every corner of it is a vertex inside a larger piece. A face-selecting simplifier (the
//! neural mesh simplifier of thesis ch. 6, beyond the thesis) keeps one where its manifold
//! pass closed the surface around three vertices without the face on them: it lies on the
//! surface that piece already covers, adds no vertex to it, and opens three or four border
//! edges in an otherwise closed output (WA, section 6.5.1; docs/mesh_simplifier_model.md,
//! "Overlays removed, wider cracks in large pieces, cracks closed by a centre vertex").

use petgraph::unionfind::UnionFind;

use crate::TriMesh;
use crate::edge_topology::edge_topology;

/// The most faces an overlay has: one face (three border edges) or two on an edge (four).
pub const MAX_OVERLAY_FACES: usize = 2;

/// `mesh` without its overlays: every piece (faces joined across edges) of at most
/// [`MAX_OVERLAY_FACES`] faces whose every corner a larger piece surrounds, with no border
/// edge of its own there. Vertices and the order of the other faces are kept; a small piece
/// with a corner of its own, or on a larger piece's border, stays.
///
/// ```
/// use meshgnn_geometry::{TriMesh, icosphere, is_watertight, remove_overlays};
/// let sphere = icosphere(1);
/// // A face across three sphere vertices that share no edge of it.
/// let mut faces = sphere.triangles().to_vec();
/// faces.push([0, 30, 40]);
/// let with_overlay = TriMesh::new(sphere.vertices().to_vec(), faces)?;
/// assert!(!is_watertight(&with_overlay));
/// assert_eq!(remove_overlays(&with_overlay).triangles(), sphere.triangles());
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn remove_overlays(mesh: &TriMesh) -> TriMesh {
    let faces = mesh.triangles();
    let topology = edge_topology(mesh);
    let mut pieces = UnionFind::<u32>::new(faces.len());
    for e in 0..topology.edge_count() {
        if let [first, rest @ ..] = topology.incidences(e) {
            for other in rest {
                pieces.union(first.face, other.face);
            }
        }
    }
    let piece = pieces.into_labeling();
    let mut size = vec![0usize; faces.len()];
    for &p in &piece {
        size[p as usize] += 1;
    }
    let large = |face: u32| size[piece[face as usize] as usize] > MAX_OVERLAY_FACES;
    // Per vertex: whether a larger piece uses it, and whether one has a border edge there.
    let mut on_large = vec![false; mesh.vertex_count()];
    for (f, t) in faces.iter().enumerate() {
        if large(f as u32) {
            for &v in t {
                on_large[v as usize] = true;
            }
        }
    }
    let mut on_large_border = vec![false; mesh.vertex_count()];
    for e in 0..topology.edge_count() {
        if let [only] = topology.incidences(e)
            && large(only.face)
        {
            on_large_border[only.from as usize] = true;
            on_large_border[only.to as usize] = true;
        }
    }
    let inside_large = |v: u32| on_large[v as usize] && !on_large_border[v as usize];
    let mut overlay = vec![true; faces.len()];
    for (f, t) in faces.iter().enumerate() {
        overlay[piece[f] as usize] &= !large(f as u32) && t.iter().all(|&v| inside_large(v));
    }
    let kept = faces
        .iter()
        .zip(&piece)
        .filter(|&(_, &p)| !overlay[p as usize])
        .map(|(t, _)| *t)
        .collect();
    mesh.with_faces_of_its_own(kept)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{icosphere, is_watertight};

    #[test]
    fn a_face_and_a_pair_across_a_sphere_go_and_the_sphere_stays() {
        let sphere = icosphere(2);
        let mut faces = sphere.triangles().to_vec();
        // A face on three sphere vertices, and a pair on four others (edge 50-60 shared).
        faces.extend([[0, 30, 70], [10, 50, 60], [50, 90, 60]]);
        let with_overlays = TriMesh::new(sphere.vertices().to_vec(), faces).unwrap();
        assert!(!is_watertight(&with_overlays));
        let cleaned = remove_overlays(&with_overlays);
        assert_eq!(cleaned.triangles(), sphere.triangles());
        assert!(is_watertight(&cleaned));
    }

    #[test]
    fn small_pieces_with_a_corner_of_their_own_or_on_a_border_stay() {
        let sphere = icosphere(1);
        let n = sphere.vertex_count() as u32;
        let mut vertices = sphere.vertices().to_vec();
        vertices.extend([[3.0, 0.0, 0.0], [3.0, 1.0, 0.0], [4.0, 0.0, 1.0]]);
        let mut faces = sphere.triangles().to_vec();
        // A face hanging from sphere vertex 0 by one corner, the others its own; a face on
        // two sphere vertices and a third of its own; a lone face on nothing.
        faces.extend([[0, n, n + 1], [5, 9, n + 2], [n, n + 1, n + 2]]);
        let faces_before = faces.clone();
        let mesh = TriMesh::new(vertices.clone(), faces).unwrap();
        assert_eq!(remove_overlays(&mesh).triangles(), &faces_before[..]);
        // A face across vertices of an open piece (the sphere less the faces around vertex
        // 1), one of them on its border: it may cover what that piece lacks, and stays.
        let mut open: Vec<[u32; 3]> = sphere
            .triangles()
            .iter()
            .filter(|t| !t.contains(&1))
            .copied()
            .collect();
        let rim = sphere
            .triangles()
            .iter()
            .find(|t| t.contains(&1))
            .and_then(|t| t.iter().copied().find(|&v| v != 1))
            .unwrap();
        let far = (0..n)
            .rev()
            .filter(|&v| v != 1 && v != rim)
            .take(2)
            .collect::<Vec<_>>();
        open.push([rim, far[0], far[1]]);
        let open = TriMesh::new(vertices, open).unwrap();
        assert_eq!(remove_overlays(&open).triangles(), open.triangles());
    }
}
