//! Lone faces closed into tetrahedra, for vertex-selecting simplifiers (the neural mesh
//! simplifier of thesis ch. 6, beyond the thesis): at a thin tip of a closed part (a limb of a
//! creature at 5 %) the face classifier may keep one face on three kept vertices that no other
//! face reaches. Dropped, the tip is lost (docs/mesh_simplifier_model.md, "Curled parts folded
//! closed"); kept, its three edges are open. Closed over one input vertex behind it, it is a
//! closed piece that still stands for the tip.

use crate::error::{Error, Result};
use crate::tri_mesh::TriMesh;
use crate::vec3::{dot, norm, sub, to_f64, triangle_cross};
use crate::vertex_neighbours::VertexNeighbours;

/// How far from the face's centroid, in its longest edges, the input is searched for the
/// vertex to close it over: the input around a tip, not the body the limb joins.
pub const LONE_FACE_REACH: f64 = 2.0;

/// How deep behind its face, in its longest edges, that vertex must lie: a face on a flat
/// stretch is left as it is.
pub const MIN_LONE_FACE_DEPTH: f64 = 0.1;

/// `selected` with each lone face closed into a tetrahedron (module docs). A face is lone when
/// none of its corners is in another face. It is closed when its corners stand for input
/// vertices (output vertex `i < kept.len()` stands for input vertex `kept[i]`) that
/// `on_open_part` does not mark (per output vertex; called only when a lone face exists). Its
/// apex: of the input vertices reached from the corners along input edges within
/// [`LONE_FACE_REACH`] longest edges of the face's centroid, the one farthest behind the face
/// (against its normal), if at least [`MIN_LONE_FACE_DEPTH`] longest edges deep. The apex is
/// appended at its input position and the three new faces run the lone face's edges
/// backwards, so the tetrahedron is closed and oriented as the face; lone faces are taken in
/// face order. Errors when `kept` is longer than the output's vertices or names a vertex
/// `input` lacks.
///
/// ```
/// use meshgnn_geometry::{TriMesh, close_lone_faces, icosphere, is_watertight};
/// let sphere = icosphere(1);
/// let kept: Vec<u32> = (0..sphere.vertex_count() as u32).collect();
/// // One face of the sphere alone: closed over a vertex inside its reach, behind it.
/// let lone = TriMesh::new(sphere.vertices().to_vec(), vec![sphere.triangles()[0]])?;
/// let closed = close_lone_faces(&sphere, &kept, &lone, Vec::new)?;
/// assert_eq!(closed.face_count(), 4);
/// assert_eq!(closed.vertex_count(), sphere.vertex_count() + 1);
/// assert!(is_watertight(&closed));
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn close_lone_faces(
    input: &TriMesh,
    kept: &[u32],
    selected: &TriMesh,
    on_open_part: impl FnOnce() -> Vec<bool>,
) -> Result<TriMesh> {
    if kept.len() > selected.vertex_count() {
        return Err(Error::InvalidParameter {
            name: "kept",
            message: format!(
                "{} kept vertices for an output of {}",
                kept.len(),
                selected.vertex_count()
            ),
        });
    }
    if let Some(&v) = kept.iter().find(|&&v| v as usize >= input.vertex_count()) {
        return Err(Error::InvalidParameter {
            name: "kept",
            message: format!("vertex {v} of {} input vertices", input.vertex_count()),
        });
    }
    let mut uses = vec![0u32; selected.vertex_count()];
    for t in selected.triangles() {
        for &v in t {
            uses[v as usize] += 1;
        }
    }
    let alone = |v: u32| uses[v as usize] == 1 && (v as usize) < kept.len();
    let mut lone: Vec<[u32; 3]> = selected
        .triangles()
        .iter()
        .filter(|t| t.iter().all(|&v| alone(v)))
        .copied()
        .collect();
    let mut vertices = selected.vertices().to_vec();
    let mut faces = selected.triangles().to_vec();
    if lone.is_empty() {
        return TriMesh::new(vertices, faces);
    }
    let on_open_part = on_open_part();
    lone.retain(|t| {
        t.iter()
            .all(|&v| on_open_part.get(v as usize) != Some(&true))
    });
    let neighbours = VertexNeighbours::new(input);
    let mut visited = vec![false; input.vertex_count()];
    for [a, b, c] in lone {
        let corners = [a, b, c].map(|v| vertices[v as usize]);
        let normal = triangle_cross(corners);
        let length = norm(normal);
        if length == 0.0 {
            continue;
        }
        let normal = normal.map(|x| x / length);
        let longest = (0..3)
            .map(|i| norm(sub(to_f64(corners[i]), to_f64(corners[(i + 1) % 3]))))
            .fold(0.0, f64::max);
        let centroid: [f64; 3] =
            std::array::from_fn(|i| corners.iter().map(|p| f64::from(p[i])).sum::<f64>() / 3.0);
        let depth = |v: u32| -dot(sub(to_f64(input.vertices()[v as usize]), centroid), normal);
        let within = |v: u32| {
            norm(sub(to_f64(input.vertices()[v as usize]), centroid)) <= LONE_FACE_REACH * longest
        };
        // A walk from the corners' input vertices along input edges, within reach.
        let mut queue: Vec<u32> = [a, b, c].map(|v| kept[v as usize]).to_vec();
        for &v in &queue {
            visited[v as usize] = true;
        }
        let mut reached = Vec::new();
        while let Some(v) = queue.pop() {
            reached.push(v);
            for &w in neighbours.of(v) {
                if !visited[w as usize] && within(w) {
                    visited[w as usize] = true;
                    queue.push(w);
                }
            }
        }
        for &v in &reached {
            visited[v as usize] = false;
        }
        // The deepest, ties to the lower index: independent of the walk's order.
        let deepest = reached
            .iter()
            .copied()
            .max_by(|&u, &w| depth(u).total_cmp(&depth(w)).then(w.cmp(&u)));
        let Some(apex) = deepest.filter(|&v| depth(v) >= MIN_LONE_FACE_DEPTH * longest) else {
            continue;
        };
        let d = vertices.len() as u32;
        vertices.push(input.vertices()[apex as usize]);
        faces.extend([[b, a, d], [c, b, d], [a, c, d]]);
    }
    TriMesh::new(vertices, faces)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{grid_plane, icosphere, is_edge_manifold, is_watertight};

    #[test]
    fn a_lone_face_closes_over_the_deepest_vertex_within_reach() {
        let sphere = icosphere(2);
        let kept: Vec<u32> = (0..sphere.vertex_count() as u32).collect();
        let face = sphere.triangles()[7];
        let lone = TriMesh::new(sphere.vertices().to_vec(), vec![face]).unwrap();
        let closed = close_lone_faces(&sphere, &kept, &lone, Vec::new).unwrap();
        assert!(is_watertight(&closed) && is_edge_manifold(&closed));
        assert_eq!(closed.triangles()[0], face);
        // The apex, by brute force: the deepest sphere vertex within reach. On a sphere every
        // vertex within reach is joined to the corners by vertices within reach.
        let corners = face.map(|v| sphere.vertices()[v as usize]);
        let normal = triangle_cross(corners);
        let normal = normal.map(|x| x / norm(normal));
        let longest = (0..3)
            .map(|i| norm(sub(to_f64(corners[i]), to_f64(corners[(i + 1) % 3]))))
            .fold(0.0, f64::max);
        let centroid: [f64; 3] =
            std::array::from_fn(|i| corners.iter().map(|p| f64::from(p[i])).sum::<f64>() / 3.0);
        let apex = (0..sphere.vertex_count())
            .map(|v| to_f64(sphere.vertices()[v]))
            .filter(|&p| norm(sub(p, centroid)) <= LONE_FACE_REACH * longest)
            .min_by(|&p, &q| {
                dot(sub(p, centroid), normal).total_cmp(&dot(sub(q, centroid), normal))
            })
            .unwrap();
        let added = to_f64(closed.vertices()[sphere.vertex_count()]);
        assert_eq!(added, apex);
        // Behind the face: inside the sphere's outward-facing face.
        assert!(dot(sub(added, centroid), normal) < -MIN_LONE_FACE_DEPTH * longest);
    }

    #[test]
    fn faces_in_a_piece_on_open_parts_or_on_a_flat_stretch_stay() {
        let sphere = icosphere(1);
        let kept: Vec<u32> = (0..sphere.vertex_count() as u32).collect();
        // Two faces sharing an edge: not lone.
        let t = sphere.triangles();
        let second = (1..t.len())
            .find(|&f| t[f].iter().filter(|v| t[0].contains(v)).count() == 2)
            .unwrap();
        let pair = TriMesh::new(sphere.vertices().to_vec(), vec![t[0], t[second]]).unwrap();
        let same = close_lone_faces(&sphere, &kept, &pair, Vec::new).unwrap();
        assert_eq!(same.triangles(), pair.triangles());
        // A lone face on an open part: left.
        let lone = TriMesh::new(sphere.vertices().to_vec(), vec![t[0]]).unwrap();
        let open = vec![true; sphere.vertex_count()];
        let left = close_lone_faces(&sphere, &kept, &lone, || open).unwrap();
        assert_eq!(left.triangles(), lone.triangles());
        // A lone face of a plane: nothing lies behind it.
        let plane = grid_plane(4, 4);
        let all: Vec<u32> = (0..plane.vertex_count() as u32).collect();
        let flat = TriMesh::new(plane.vertices().to_vec(), vec![plane.triangles()[9]]).unwrap();
        let kept_flat = close_lone_faces(&plane, &all, &flat, Vec::new).unwrap();
        assert_eq!(kept_flat.triangles(), flat.triangles());
        assert_eq!(kept_flat.vertex_count(), plane.vertex_count());
    }

    #[test]
    fn bad_kept_vertices_are_errors() {
        let sphere = icosphere(0);
        let lone = TriMesh::new(sphere.vertices().to_vec(), vec![sphere.triangles()[0]]).unwrap();
        let too_many: Vec<u32> = (0..sphere.vertex_count() as u32 + 1).collect();
        assert!(close_lone_faces(&sphere, &too_many, &lone, Vec::new).is_err());
        assert!(close_lone_faces(&sphere, &[0, 1, 99], &lone, Vec::new).is_err());
    }
}
