//! Overlays: a lone face or a pair of faces that shares no edge with the rest of a mesh while
//! every corner of it is a vertex inside a larger piece. A face-selecting simplifier (the
//! neural mesh simplifier of thesis ch. 6, beyond the thesis) keeps one where its manifold
//! pass closed the surface around three vertices without the face on them: it lies on the
//! surface that piece already covers, adds no vertex to it, and opens three or four border
//! edges in an otherwise closed output (WA, section 6.5.1; docs/mesh_simplifier_model.md,
//! "Overlays removed, wider cracks in large pieces, cracks closed by a centre vertex").
//! *Flaps* are their kin on a closed surface: a lone face or pair hanging from it by a corner
//! or two, a fin sticking out of it ("Flaps on closed pieces dropped").

use petgraph::unionfind::UnionFind;

use crate::TriMesh;
use crate::edge_topology::{EdgeTopology, edge_topology};

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
    let pieces = Pieces::new(mesh);
    // Per vertex: whether a larger piece uses it, and whether one has a border edge there.
    let mut on_large = vec![false; mesh.vertex_count()];
    let mut on_large_border = vec![false; mesh.vertex_count()];
    for (f, t) in mesh.triangles().iter().enumerate() {
        if pieces.large(f) {
            for &v in t {
                on_large[v as usize] = true;
            }
        }
    }
    for (from, to, face) in pieces.border_edges() {
        if pieces.large(face as usize) {
            on_large_border[from as usize] = true;
            on_large_border[to as usize] = true;
        }
    }
    let inside_large = |v: u32| on_large[v as usize] && !on_large_border[v as usize];
    let faces = mesh.triangles();
    pieces.drop_small(mesh, |f| faces[f].iter().all(|&v| inside_large(v)))
}

/// `mesh` without its flaps: every piece (faces joined across edges) of at most
/// [`MAX_OVERLAY_FACES`] faces with a corner on a larger piece that has no border edge (a
/// closed surface), and no corner where `on_open_part()` holds. Such a face hangs from that
/// surface by one or two corners, a fin whose own corners no face of the surface reaches; its
/// border edges are the only ones left in an otherwise closed output. `on_open_part()` marks
/// vertices that stand for an open part of a simplifier's input, where a border belongs
/// (vertices past its end are not marked); it is called only when a flap is found. Vertices
/// and the order of the other faces are kept; a small piece touching only open pieces, or
/// none, stays.
///
/// ```
/// use meshgnn_geometry::{TriMesh, icosphere, is_watertight, remove_flaps};
/// let sphere = icosphere(1);
/// let n = sphere.vertex_count() as u32;
/// // A face hanging from sphere vertex 0 by one corner.
/// let mut vertices = sphere.vertices().to_vec();
/// vertices.extend([[2.0, 0.0, 0.0], [2.0, 1.0, 0.0]]);
/// let mut faces = sphere.triangles().to_vec();
/// faces.push([0, n, n + 1]);
/// let with_flap = TriMesh::new(vertices, faces)?;
/// assert!(!is_watertight(&with_flap));
/// assert_eq!(remove_flaps(&with_flap, Vec::new).triangles(), sphere.triangles());
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn remove_flaps(mesh: &TriMesh, on_open_part: impl FnOnce() -> Vec<bool>) -> TriMesh {
    let pieces = Pieces::new(mesh);
    let mut open = vec![false; mesh.face_count()];
    for (_, _, face) in pieces.border_edges() {
        open[pieces.label[face as usize] as usize] = true;
    }
    let mut on_closed_large = vec![false; mesh.vertex_count()];
    for (f, t) in mesh.triangles().iter().enumerate() {
        if pieces.large(f) && !open[pieces.label[f] as usize] {
            for &v in t {
                on_closed_large[v as usize] = true;
            }
        }
    }
    // Per piece: whether it touches a closed larger piece, and whether a corner is on an open
    // part.
    let mut touches_closed = vec![false; mesh.face_count()];
    for (f, t) in mesh.triangles().iter().enumerate() {
        if !pieces.large(f) {
            touches_closed[pieces.label[f] as usize] |=
                t.iter().any(|&v| on_closed_large[v as usize]);
        }
    }
    if !touches_closed.contains(&true) {
        return mesh.clone();
    }
    let on_open_part = on_open_part();
    let mut on_open = vec![false; mesh.face_count()];
    for (f, t) in mesh.triangles().iter().enumerate() {
        on_open[pieces.label[f] as usize] |= t
            .iter()
            .any(|&v| on_open_part.get(v as usize).copied().unwrap_or(false));
    }
    pieces.drop_small(mesh, |f| {
        let p = pieces.label[f] as usize;
        touches_closed[p] && !on_open[p]
    })
}

/// The pieces of a mesh: faces joined across edges (any number of faces per edge).
struct Pieces {
    topology: EdgeTopology,
    /// Per face, its piece (a face index).
    label: Vec<u32>,
    /// Per piece label, its face count.
    size: Vec<usize>,
}

impl Pieces {
    fn new(mesh: &TriMesh) -> Self {
        let topology = edge_topology(mesh);
        let mut pieces = UnionFind::<u32>::new(mesh.face_count());
        for e in 0..topology.edge_count() {
            if let [first, rest @ ..] = topology.incidences(e) {
                for other in rest {
                    pieces.union(first.face, other.face);
                }
            }
        }
        let label = pieces.into_labeling();
        let mut size = vec![0usize; label.len()];
        for &p in &label {
            size[p as usize] += 1;
        }
        Self {
            topology,
            label,
            size,
        }
    }

    /// Whether face `f` lies in a piece of more than [`MAX_OVERLAY_FACES`] faces.
    fn large(&self, f: usize) -> bool {
        self.size[self.label[f] as usize] > MAX_OVERLAY_FACES
    }

    /// The edges with one face: `(from, to, face)`.
    fn border_edges(&self) -> impl Iterator<Item = (u32, u32, u32)> + '_ {
        (0..self.topology.edge_count()).filter_map(|e| match self.topology.incidences(e) {
            [only] => Some((only.from, only.to, only.face)),
            _ => None,
        })
    }

    /// `mesh` without the small pieces (at most [`MAX_OVERLAY_FACES`] faces) every face `f`
    /// of which satisfies `drop(f)`.
    fn drop_small(&self, mesh: &TriMesh, drop: impl Fn(usize) -> bool) -> TriMesh {
        let faces = mesh.triangles();
        let mut dropped = vec![true; faces.len()];
        for f in 0..faces.len() {
            dropped[self.label[f] as usize] &= !self.large(f) && drop(f);
        }
        let kept = faces
            .iter()
            .zip(&self.label)
            .filter(|&(_, &p)| !dropped[p as usize])
            .map(|(t, _)| *t)
            .collect();
        mesh.with_faces_of_its_own(kept)
    }
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

    #[test]
    fn flaps_on_a_closed_surface_go_and_those_on_an_open_one_stay() {
        let sphere = icosphere(1);
        let n = sphere.vertex_count() as u32;
        let mut vertices = sphere.vertices().to_vec();
        vertices.extend([
            [2.0, 0.0, 0.0],
            [2.0, 1.0, 0.0],
            [3.0, 0.0, 1.0],
            [9.0, 9.0, 9.0],
            [9.0, 8.0, 9.0],
            [8.0, 9.0, 9.0],
        ]);
        // A pair hanging from sphere vertex 0 (its second face touches the sphere nowhere) and
        // a lone face touching nothing; then a fan from vertex 5 that joins the lone face into
        // a piece of four (not small).
        let mut faces = sphere.triangles().to_vec();
        let pair = [[0, n, n + 1], [n, n + 2, n + 1]];
        let lone = [n + 3, n + 4, n + 5];
        let fan = [[5, n, n + 3], [5, n + 3, n + 4], [5, n + 4, n + 5]];
        faces.extend(pair);
        faces.push(lone);
        let mesh = TriMesh::new(vertices.clone(), faces).unwrap();
        let mut expected = sphere.triangles().to_vec();
        expected.push(lone);
        assert_eq!(remove_flaps(&mesh, Vec::new).triangles(), &expected[..]);
        let mut with_fan = expected.clone();
        with_fan.extend(fan);
        let fan_mesh = TriMesh::new(vertices.clone(), with_fan.clone()).unwrap();
        assert_eq!(remove_flaps(&fan_mesh, Vec::new).triangles(), &with_fan[..]);
        // The same pair on the sphere less one face (a piece with a border) stays.
        let mut open = sphere.triangles()[1..].to_vec();
        open.extend(pair);
        let open = TriMesh::new(vertices, open).unwrap();
        assert_eq!(remove_flaps(&open, Vec::new).triangles(), open.triangles());
    }

    #[test]
    fn a_flap_with_a_corner_on_an_open_part_stays() {
        let sphere = icosphere(1);
        let n = sphere.vertex_count() as u32;
        let mut vertices = sphere.vertices().to_vec();
        vertices.extend([[2.0, 0.0, 0.0], [2.0, 1.0, 0.0]]);
        let mut faces = sphere.triangles().to_vec();
        faces.push([0, n, n + 1]);
        let mesh = TriMesh::new(vertices, faces).unwrap();
        let mut on_open_part = vec![false; mesh.vertex_count()];
        on_open_part[n as usize + 1] = true;
        assert_eq!(
            remove_flaps(&mesh, || on_open_part).triangles(),
            mesh.triangles()
        );
        // Marks on the sphere alone do not keep it.
        let mut sphere_marked = vec![false; mesh.vertex_count()];
        sphere_marked[7] = true;
        assert_eq!(
            remove_flaps(&mesh, || sphere_marked).triangles(),
            sphere.triangles()
        );
    }
}
