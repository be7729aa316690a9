//! Pinched vertices mended, for vertex-selecting simplifiers (the neural mesh simplifier of
//! thesis ch. 6, beyond the thesis). The faces the network keeps may close a limb and the body
//! it joins as two closed pieces that touch at a vertex or two, instead of one surface through
//! the joint. Such a vertex carries two fans: half-edge structures refuse it, and splitting it
//! cuts the limb off, which moves the Laplacian spectrum (LE) by a whole zero eigenvalue
//! (docs/mesh_simplifier_model.md, "Pinched vertices bridged").
//!
//! Two closed fans of different pieces at `u` are joined by a bridge: one face of each,
//! `(u, a, b)` and `(u, c, d)`, is removed, and the gap closed by `(u, a, d)`, `(u, c, b)` and
//! the quadrilateral `a b c d` in two faces. That is a connected sum: the pieces become one
//! surface of the same genus and orientation, with `u` on a single fan. Of the face pairs
//! ([`BRIDGE_CANDIDATES`] faces of each fan, those nearest the other) and diagonals that add
//! no edge the mesh already has, the one of least new area is made. The largest closed fan
//! at `u` is bridged to each other closed fan of another piece in turn, to at most
//! [`MAX_BRIDGES_PER_VERTEX`].
//!
//! The other fans are split: each gets a copy of the vertex. Within one piece (the second
//! contact of two bridged pieces, two fans of one open sheet) that cuts nothing apart; an open
//! fan at another piece's vertex (a lone face, a rim) is cut off rather than left pinched.
//! Only closed fans of different pieces that no bridge fits stay.

use std::collections::{HashMap, HashSet};

use petgraph::unionfind::UnionFind;

use crate::cap_flips::{EdgeFaces, add_face, edge_key, remove_face};
use crate::error::Result;
use crate::manifold::{fans_around, non_manifold_vertices};
use crate::tri_mesh::TriMesh;
use crate::vec3::{norm, sub, to_f64, triangle_cross};

/// Faces of each fan a bridge may go through: those nearest the other fan. It bounds the
/// search on a vertex of large fans; the fans of the neural simplifier's pinches hold at most
/// a dozen faces, and their least-area bridge goes through faces that face each other.
pub const BRIDGE_CANDIDATES: usize = 8;

/// Other fans a vertex's largest closed fan is bridged to at most (the largest first); of the
/// rest, closed fans of other pieces stay and the others are split. It bounds the work on a
/// vertex of thousands of fans, a file made to be slow.
pub const MAX_BRIDGES_PER_VERTEX: usize = 64;

/// `mesh` with its pinched vertices bridged or split (module docs): the faces of `mesh` in
/// their order less the bridged ones, then the bridges' faces; the vertices of `mesh`, then
/// the copies made by splits (so a vertex index of `mesh` still names the same point).
///
/// ```
/// use meshgnn_geometry::{TriMesh, bridge_pinched_vertices, is_vertex_manifold, is_watertight};
/// // Two tetrahedra sharing their apex 0, one above and one below the plane z = 0.
/// let v = vec![
///     [0.0, 0.0, 0.0],
///     [1.0, 0.0, 1.0], [-0.5, 0.9, 1.0], [-0.5, -0.9, 1.0],
///     [1.0, 0.0, -1.0], [-0.5, 0.9, -1.0], [-0.5, -0.9, -1.0],
/// ];
/// let upper = [[0, 2, 1], [0, 3, 2], [0, 1, 3], [1, 2, 3]];
/// let lower = [[0, 4, 5], [0, 5, 6], [0, 6, 4], [4, 6, 5]];
/// let pinched = TriMesh::new(v, [upper, lower].concat())?;
/// let bridged = bridge_pinched_vertices(&pinched)?;
/// assert!(is_vertex_manifold(&bridged) && is_watertight(&bridged));
/// assert_eq!((bridged.vertex_count(), bridged.face_count()), (7, 10));
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn bridge_pinched_vertices(mesh: &TriMesh) -> Result<TriMesh> {
    let pinched = non_manifold_vertices(mesh);
    if pinched.is_empty() {
        return Ok(mesh.clone());
    }
    let mut surgery = Surgery::new(mesh, &pinched);
    for &u in &pinched {
        surgery.bridge_fans(u);
        surgery.split_fans(u);
    }
    surgery.into_mesh()
}

/// A bridge at `u` (module docs): the two faces it removes and the four it adds.
struct Bridge {
    removed: [usize; 2],
    added: [[u32; 3]; 4],
    area: f64,
}

/// The mesh under repair: faces with removal marks, their edges, the faces around each
/// pinched vertex and the pieces (edge-connected face sets) they belong to.
struct Surgery {
    vertices: Vec<[f32; 3]>,
    faces: Vec<[u32; 3]>,
    removed: Vec<bool>,
    edge_faces: EdgeFaces,
    around: HashMap<u32, Vec<u32>>,
    /// Pieces over the input's faces; a bridge's face counts as the input face it replaced.
    pieces: UnionFind<usize>,
    anchor: Vec<usize>,
}

impl Surgery {
    fn new(mesh: &TriMesh, pinched: &[u32]) -> Self {
        let faces = mesh.triangles().to_vec();
        let mut edge_faces = EdgeFaces::new();
        let mut around: HashMap<u32, Vec<u32>> = pinched.iter().map(|&v| (v, Vec::new())).collect();
        for (f, t) in faces.iter().enumerate() {
            add_face(&mut edge_faces, f, t);
            for v in t {
                if let Some(list) = around.get_mut(v) {
                    list.push(f as u32);
                }
            }
        }
        let mut pieces = UnionFind::new(faces.len());
        for sharing in edge_faces.values() {
            for pair in sharing.windows(2) {
                pieces.union(pair[0].0, pair[1].0);
            }
        }
        Self {
            vertices: mesh.vertices().to_vec(),
            removed: vec![false; faces.len()],
            anchor: (0..faces.len()).collect(),
            faces,
            edge_faces,
            around,
            pieces,
        }
    }

    fn piece(&self, f: u32) -> usize {
        self.pieces.find(self.anchor[f as usize])
    }

    /// The fans around `u`, each a list of faces, ascending, in the order of their first.
    fn fans(&self, u: u32) -> Vec<Vec<u32>> {
        let faces = self.around.get(&u).map_or(&[][..], Vec::as_slice);
        let (labels, _) = fans_around(u, faces, &self.faces);
        let mut labelled: Vec<(usize, u32)> =
            labels.into_iter().zip(faces.iter().copied()).collect();
        labelled.sort_unstable();
        let mut fans: Vec<Vec<u32>> = labelled
            .chunk_by(|a, b| a.0 == b.0)
            .map(|fan| fan.iter().map(|&(_, f)| f).collect())
            .collect();
        fans.sort_unstable_by_key(|fan| fan[0]);
        fans
    }

    /// True when every edge of the fan at `u` has two faces.
    fn is_closed(&self, u: u32, fan: &[u32]) -> bool {
        fan.iter().all(|&f| {
            self.faces[f as usize]
                .iter()
                .filter(|&&w| w != u)
                .all(|&w| {
                    self.edge_faces
                        .get(&edge_key(u, w))
                        .is_some_and(|s| s.len() == 2)
                })
        })
    }

    /// Bridges the largest closed fan at `u` to each other closed fan of another piece in
    /// turn (module docs), the fan growing with each bridge.
    fn bridge_fans(&mut self, u: u32) {
        let mut fans: Vec<Vec<u32>> = self
            .fans(u)
            .into_iter()
            .filter(|fan| self.is_closed(u, fan))
            .collect();
        if fans.len() < 2 {
            return;
        }
        fans.sort_by_key(|fan| std::cmp::Reverse(fan.len()));
        let mut hub = fans[0].clone();
        for other in fans.iter().skip(1).take(MAX_BRIDGES_PER_VERTEX) {
            if self.piece(hub[0]) == self.piece(other[0]) {
                continue;
            }
            let Some(bridge) = self.least_area_bridge(u, &hub, other) else {
                continue;
            };
            let [f, g] = bridge.removed;
            self.pieces.union(self.anchor[f], self.anchor[g]);
            for r in bridge.removed {
                self.remove(r);
            }
            for t in bridge.added {
                self.add(t, f);
            }
            // The first added face, `(u, a, d)`, lies in the joined fan.
            let joined = (self.faces.len() - 4) as u32;
            match self.fans(u).into_iter().find(|fan| fan.contains(&joined)) {
                Some(fan) => hub = fan,
                None => return,
            }
        }
    }

    /// The least-area bridge between fans `first` and `second` at `u`, through one of the
    /// [`BRIDGE_CANDIDATES`] faces of each nearest the other fan.
    fn least_area_bridge(&self, u: u32, first: &[u32], second: &[u32]) -> Option<Bridge> {
        let mut best: Option<Bridge> = None;
        for f in self.nearest_faces(first, second) {
            for g in self.nearest_faces(second, first) {
                for diagonal in [false, true] {
                    if let Some(bridge) = self.bridge(u, f, g, diagonal)
                        && best.as_ref().is_none_or(|b| bridge.area < b.area)
                    {
                        best = Some(bridge);
                    }
                }
            }
        }
        best
    }

    /// The [`BRIDGE_CANDIDATES`] faces of `fan` whose centroids lie nearest the mean centroid
    /// of `other`'s, nearest first (ties in fan order).
    fn nearest_faces(&self, fan: &[u32], other: &[u32]) -> Vec<u32> {
        let centroid = |f: u32| -> [f64; 3] {
            let corners = self.faces[f as usize].map(|v| to_f64(self.vertices[v as usize]));
            std::array::from_fn(|k| corners.iter().map(|p| p[k]).sum::<f64>() / 3.0)
        };
        let mut centre = [0.0; 3];
        for &g in other {
            let c = centroid(g);
            for k in 0..3 {
                centre[k] += c[k] / other.len() as f64;
            }
        }
        let mut by_distance: Vec<(f64, u32)> = fan
            .iter()
            .map(|&f| (norm(sub(centroid(f), centre)), f))
            .collect();
        by_distance.sort_by(|a, b| a.0.total_cmp(&b.0));
        by_distance
            .into_iter()
            .take(BRIDGE_CANDIDATES)
            .map(|(_, f)| f)
            .collect()
    }

    /// The bridge through faces `f` and `g` at `u`, its quadrilateral split along `bd` when
    /// `diagonal`, else along `ac`; `None` when its corners repeat, it would add an edge the
    /// mesh has, or a new face has no area.
    fn bridge(&self, u: u32, f: u32, g: u32, diagonal: bool) -> Option<Bridge> {
        let [a, b] = after(self.faces[f as usize], u);
        let [c, d] = after(self.faces[g as usize], u);
        let corners = [a, b, c, d];
        if (0..4).any(|i| corners[i + 1..].contains(&corners[i])) {
            return None;
        }
        let (quad, cut) = if diagonal {
            ([[a, b, d], [b, c, d]], (b, d))
        } else {
            ([[a, b, c], [a, c, d]], (a, c))
        };
        let added = [[u, a, d], [u, c, b], quad[0], quad[1]];
        if [(a, d), (c, b), cut]
            .iter()
            .any(|&(p, q)| self.edge_faces.contains_key(&edge_key(p, q)))
        {
            return None;
        }
        let areas = added.map(|t| 0.5 * norm(triangle_cross(t.map(|v| self.vertices[v as usize]))));
        areas.iter().all(|&a| a > 0.0).then(|| Bridge {
            removed: [f as usize, g as usize],
            added,
            area: areas.iter().sum(),
        })
    }

    /// Gives a copy of `u` to every fan but the first (closed fans first, then the larger),
    /// except a closed fan of a piece no earlier fan is in: one the bridges could not join.
    fn split_fans(&mut self, u: u32) {
        let mut fans: Vec<(bool, Vec<u32>)> = self
            .fans(u)
            .into_iter()
            .map(|fan| (self.is_closed(u, &fan), fan))
            .collect();
        fans.sort_by_key(|(closed, fan)| (!closed, std::cmp::Reverse(fan.len())));
        let mut pieces_seen: HashSet<usize> = HashSet::new();
        let mut moved_away: HashSet<u32> = HashSet::new();
        for (k, (closed, fan)) in fans.into_iter().enumerate() {
            let new_piece = pieces_seen.insert(self.piece(fan[0]));
            if k == 0 || (closed && new_piece) {
                continue;
            }
            let copy = self.vertices.len() as u32;
            self.vertices.push(self.vertices[u as usize]);
            for f in fan {
                let t = self.faces[f as usize];
                remove_face(&mut self.edge_faces, f as usize, &t);
                let moved = t.map(|v| if v == u { copy } else { v });
                self.faces[f as usize] = moved;
                add_face(&mut self.edge_faces, f as usize, &moved);
                moved_away.insert(f);
            }
        }
        if let Some(list) = self.around.get_mut(&u) {
            list.retain(|f| !moved_away.contains(f));
        }
    }

    fn remove(&mut self, f: usize) {
        let t = self.faces[f];
        self.removed[f] = true;
        remove_face(&mut self.edge_faces, f, &t);
        for v in t {
            if let Some(list) = self.around.get_mut(&v) {
                list.retain(|&h| h as usize != f);
            }
        }
    }

    /// Appends face `t`, in the piece of input face `anchor`.
    fn add(&mut self, t: [u32; 3], anchor: usize) {
        let f = self.faces.len();
        self.faces.push(t);
        self.removed.push(false);
        self.anchor.push(self.anchor[anchor]);
        add_face(&mut self.edge_faces, f, &t);
        for v in t {
            if let Some(list) = self.around.get_mut(&v) {
                list.push(f as u32);
            }
        }
    }

    fn into_mesh(self) -> Result<TriMesh> {
        let faces = self
            .faces
            .into_iter()
            .zip(self.removed)
            .filter_map(|(t, removed)| (!removed).then_some(t))
            .collect();
        TriMesh::new(self.vertices, faces)
    }
}

/// The corners of `t` after `u`, in its order: `[a, b]` for `t = (u, a, b)` rotated.
fn after(t: [u32; 3], u: u32) -> [u32; 2] {
    match t.iter().position(|&v| v == u) {
        Some(0) => [t[1], t[2]],
        Some(1) => [t[2], t[0]],
        _ => [t[0], t[1]],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{
        connected_components, icosphere, is_edge_manifold, is_vertex_manifold, is_watertight,
        mesh_report,
    };

    /// An octahedron of half-height `h` around `centre`: poles `(centre ± h·z)` first.
    fn octahedron(centre: [f32; 3], h: f32) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
        let [x, y, z] = centre;
        let vertices = vec![
            [x, y, z + h],
            [x, y, z - h],
            [x + 0.5, y, z],
            [x, y + 0.5, z],
            [x - 0.5, y, z],
            [x, y - 0.5, z],
        ];
        let mut faces = Vec::new();
        for i in 0..4u32 {
            let (p, q) = (2 + i, 2 + (i + 1) % 4);
            faces.push([0, p, q]);
            faces.push([1, q, p]);
        }
        (vertices, faces)
    }

    /// Two octahedra joined as `glue` says: vertex `i` of the second is vertex `glue[i]` of
    /// the first when `Some`.
    fn glued(second_centre: [f32; 3], glue: [Option<u32>; 6]) -> TriMesh {
        let (mut vertices, mut faces) = octahedron([0.0, 0.0, 0.0], 1.0);
        let (others, other_faces) = octahedron(second_centre, 1.0);
        let mut index = [0u32; 6];
        for (i, p) in others.into_iter().enumerate() {
            index[i] = glue[i].unwrap_or_else(|| {
                vertices.push(p);
                vertices.len() as u32 - 1
            });
        }
        faces.extend(other_faces.iter().map(|t| t.map(|v| index[v as usize])));
        TriMesh::new(vertices, faces).unwrap()
    }

    fn assert_one_closed_oriented_manifold(mesh: &TriMesh) {
        let report = mesh_report(mesh);
        assert!(is_vertex_manifold(mesh) && is_edge_manifold(mesh) && is_watertight(mesh));
        assert_eq!(report.misoriented_edges, 0);
        assert_eq!(connected_components(mesh).0, 1);
    }

    #[test]
    fn two_pieces_touching_at_a_vertex_become_one_surface() {
        // The second octahedron stands on the first's top pole.
        let mesh = glued([0.0, 0.0, 2.0], [None, Some(0), None, None, None, None]);
        assert!(!is_vertex_manifold(&mesh));
        let bridged = bridge_pinched_vertices(&mesh).unwrap();
        assert_one_closed_oriented_manifold(&bridged);
        // Two faces removed, four added; no vertex added.
        assert_eq!(bridged.face_count(), mesh.face_count() + 2);
        assert_eq!(bridged.vertices(), mesh.vertices());
        // Euler characteristic 2: a sphere, as the connected sum of two.
        let edges = 3 * bridged.face_count() / 2;
        assert_eq!(bridged.vertex_count() + bridged.face_count() - edges, 2);
    }

    #[test]
    fn a_second_contact_of_bridged_pieces_is_split() {
        // Both poles shared: the second octahedron is the first's, its equator moved aside.
        let mesh = glued([2.0, 0.0, 0.0], [Some(0), Some(1), None, None, None, None]);
        assert_eq!(non_manifold_vertices(&mesh), vec![0, 1]);
        let mended = bridge_pinched_vertices(&mesh).unwrap();
        assert_one_closed_oriented_manifold(&mended);
        // One bridge (at vertex 0) and one copy of vertex 1, at its position.
        assert_eq!(mended.face_count(), mesh.face_count() + 2);
        assert_eq!(mended.vertex_count(), mesh.vertex_count() + 1);
        assert_eq!(mended.vertices().last(), Some(&mesh.vertices()[1]));
    }

    #[test]
    fn open_fans_at_a_pinch_are_cut_off_and_manifold_meshes_stay() {
        // A bowtie: two lone faces sharing vertex 0. The second gets a copy of it.
        let v = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [-1.0, 0.0, 0.0],
            [-1.0, -1.0, 0.0],
        ];
        let bowtie = TriMesh::new(v.clone(), vec![[0, 1, 2], [0, 3, 4]]).unwrap();
        let split = bridge_pinched_vertices(&bowtie).unwrap();
        assert_eq!(split.triangles(), &[[0, 1, 2], [5, 3, 4]]);
        assert_eq!(split.vertices()[5], v[0]);
        // A lone face hanging from an octahedron's pole: cut off, the octahedron untouched.
        let (mut vertices, mut faces) = octahedron([0.0, 0.0, 0.0], 1.0);
        vertices.extend([[0.5, 0.0, 2.0], [0.0, 0.5, 2.0]]);
        faces.push([0, 6, 7]);
        let hanging = TriMesh::new(vertices, faces.clone()).unwrap();
        let cut = bridge_pinched_vertices(&hanging).unwrap();
        assert!(is_vertex_manifold(&cut) && is_edge_manifold(&cut));
        assert_eq!(cut.triangles()[..8], faces[..8]);
        assert_eq!(cut.triangles()[8], [8, 6, 7]);
        let sphere = icosphere(2);
        assert_eq!(bridge_pinched_vertices(&sphere).unwrap(), sphere);
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
        /// Octahedra added one by one, each with its top pole on a vertex already there and,
        /// when `second` says, its bottom pole on another: one closed, oriented 2-manifold of
        /// genus 0 comes out, whatever the contacts.
        #[test]
        fn octahedra_touching_anywhere_become_one_sphere(
            contacts in proptest::collection::vec((0usize..1000, 0usize..1000, 0u8..3), 1..6),
        ) {
            let (mut vertices, mut faces) = octahedron([0.0, 0.0, 0.0], 1.0);
            for (k, &(top, bottom, second)) in contacts.iter().enumerate() {
                let angle = k as f32 * 2.4;
                let centre = [3.0 * angle.cos(), 3.0 * angle.sin(), 0.7 * k as f32];
                let (others, other_faces) = octahedron(centre, 1.0);
                let count = vertices.len();
                let top = (top % count) as u32;
                let bottom = (bottom % count) as u32;
                let mut index = [0u32; 6];
                for (i, p) in others.into_iter().enumerate() {
                    index[i] = match i {
                        0 => top,
                        1 if second == 0 && bottom != top => bottom,
                        _ => {
                            vertices.push(p);
                            vertices.len() as u32 - 1
                        }
                    };
                }
                faces.extend(other_faces.iter().map(|t| t.map(|v| index[v as usize])));
            }
            let mesh = TriMesh::new(vertices, faces).unwrap();
            proptest::prop_assume!(is_edge_manifold(&mesh));
            let mended = bridge_pinched_vertices(&mesh).unwrap();
            assert_one_closed_oriented_manifold(&mended);
            let edges = 3 * mended.face_count() / 2;
            proptest::prop_assert_eq!(mended.vertex_count() + mended.face_count() - edges, 2);
        }
    }

    #[test]
    fn dozens_of_pieces_at_one_vertex_become_one_surface() {
        // 60 tetrahedra sharing their apex, their bases on a ring around it.
        let mut vertices = vec![[0.0f32, 0.0, 0.0]];
        let mut faces = Vec::new();
        for k in 0..60 {
            let angle = k as f32 * std::f32::consts::TAU / 60.0;
            let (c, s) = (angle.cos(), angle.sin());
            let base = vertices.len() as u32;
            vertices.extend([
                [2.0 * c, 2.0 * s, 0.1],
                [2.0 * c, 2.0 * s, -0.1],
                [2.2 * c - 0.01 * s, 2.2 * s + 0.01 * c, 0.0],
            ]);
            let [a, b, d] = [base, base + 1, base + 2];
            faces.extend([[0, a, b], [0, b, d], [0, d, a], [a, d, b]]);
        }
        let mesh = TriMesh::new(vertices, faces).unwrap();
        assert_eq!(non_manifold_vertices(&mesh), vec![0]);
        let bridged = bridge_pinched_vertices(&mesh).unwrap();
        assert!(is_vertex_manifold(&bridged) && is_edge_manifold(&bridged));
        assert!(is_watertight(&bridged));
        assert_eq!(connected_components(&bridged).0, 1);
        assert_eq!(bridged.face_count(), mesh.face_count() + 2 * 59);
    }

    #[test]
    fn thousands_of_pieces_at_one_vertex_end_quickly() {
        // 5 000 tetrahedra sharing their apex: the largest fan is bridged to 64 others.
        let mut vertices = vec![[0.0f32, 0.0, 0.0]];
        let mut faces = Vec::new();
        for k in 0..5000u32 {
            let angle = k as f32 * 0.001_256_6;
            let (c, s) = (angle.cos(), angle.sin());
            let base = vertices.len() as u32;
            vertices.extend([
                [2.0 * c, 2.0 * s, 0.1],
                [2.0 * c, 2.0 * s, -0.1],
                [2.2 * c, 2.2 * s, 0.0],
            ]);
            let [a, b, d] = [base, base + 1, base + 2];
            faces.extend([[0, a, b], [0, b, d], [0, d, a], [a, d, b]]);
        }
        let mesh = TriMesh::new(vertices, faces).unwrap();
        let started = std::time::Instant::now();
        let bridged = bridge_pinched_vertices(&mesh).unwrap();
        assert!(started.elapsed().as_secs() < 20, "{:?}", started.elapsed());
        assert_eq!(
            bridged.face_count(),
            mesh.face_count() + 2 * MAX_BRIDGES_PER_VERTEX
        );
        assert!(is_edge_manifold(&bridged) && is_watertight(&bridged));
    }

    #[test]
    fn three_pieces_at_one_vertex_are_bridged_in_turn() {
        // Two more octahedra, one above the first and one beside it, each with a vertex moved
        // onto the first's top pole: vertex 0 carries three closed fans.
        let (mut vertices, mut faces) = octahedron([0.0, 0.0, 0.0], 1.0);
        for centre in [[0.0, 0.0, 2.0], [1.5, 0.0, 1.0]] {
            let (others, other_faces) = octahedron(centre, 1.0);
            let base = vertices.len() as u32;
            vertices.extend(&others);
            faces.extend(other_faces.iter().map(|t| t.map(|v| base + v)));
        }
        // Put the second's bottom pole and the third's left equator vertex on vertex 0.
        for t in &mut faces[8..] {
            for v in t.iter_mut() {
                if *v == 7 || *v == 16 {
                    *v = 0;
                }
            }
        }
        let mesh = TriMesh::new(vertices, faces).unwrap();
        assert_eq!(non_manifold_vertices(&mesh), vec![0]);
        let bridged = bridge_pinched_vertices(&mesh).unwrap();
        assert_one_closed_oriented_manifold(&bridged);
        assert_eq!(bridged.face_count(), mesh.face_count() + 4);
    }
}
