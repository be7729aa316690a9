//! Cap triangles flipped away: a cap has one corner on its opposite edge, to within the
//! rounding of its `f32` coordinates, so it has no area and an angle of 180°. A simplifier
//! that keeps input vertices (the neural mesh simplifier of thesis ch. 6) keeps several along
//! a straight crease, and a triangle through three of them is such a cap. It adds no surface,
//! but its 180° angle gives the cotangent Laplacian a weight of about `−1/ε`, negative and
//! unbounded, so the Laplacian stops being positive semi-definite and its eigenpairs — the
//! spectral error LE of eq. 6.16 — follow the rounding, or the eigen-solver fails.
//!
//! The edge opposite the flat corner is flipped with the face across it: cap `(a, c, b)`, `b`
//! on `ac`, and neighbour `(c, a, d)` become `(b, a, d)` and `(b, d, c)`, the two halves of the
//! neighbour. The surface, the border and the orientation stay; both new faces have area.
//!
//! # Conventions
//! - A corner is flat when it projects strictly inside the opposite edge and lies within
//!   [`CAP_RELATIVE_HEIGHT`] of that edge's length from it, or of the corners' largest
//!   coordinate where that is larger: away from the origin, the rounding of `f32`
//!   coordinates exceeds 10⁻⁶ of a short edge (a fandisk output kept a cap 1.07·10⁻⁶ of its
//!   edge high, whose coordinates, 14 times its edge, round by 1.5·10⁻⁶ of it).
//! - An edge is flipped only when exactly one other face uses it, in the opposite direction,
//!   the new edge `bd` is not an edge yet and `d` is not itself flat on `ac`; otherwise the cap
//!   stays (on a border, on a non-manifold edge).
//! - Passes over the remaining caps repeat while one flips, at most [`MAX_PASSES`]: a flip
//!   can clear the way for another (caps side by side along one crease).

use std::collections::HashMap;

use crate::error::Result;
use crate::tri_mesh::TriMesh;
use crate::vec3::{cross, dot, norm, sub, to_f64};

/// Height of a flat corner over its opposite edge, relative to that edge's length or to the
/// corners' largest coordinate, whichever is larger: about 16 `f32` rounding steps (2⁻²⁴ ≈
/// 6·10⁻⁸ relative), so that only corners on the edge to within the rounding of the
/// coordinates count.
pub const CAP_RELATIVE_HEIGHT: f64 = 1e-6;

/// Passes over the caps at most.
const MAX_PASSES: usize = 8;

/// Faces per undirected edge, each with the direction it runs the edge in.
pub(crate) type EdgeFaces = HashMap<(u32, u32), Vec<(usize, bool)>>;

/// `mesh` with its caps flipped away (module docs); vertices unchanged, faces in the same
/// order with each flipped pair rewritten in place.
///
/// ```
/// use meshgnn_geometry::{TriMesh, flip_caps};
/// // Square (0, 1, 2, 3) split by diagonal 0-2, with vertex 4 the middle of that diagonal:
/// // face (0, 2, 4) is a cap; flipping 0-2 gives two faces that cover the other half.
/// let v = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
/// let v = [v, vec![[0.5, 0.5, 0.0]]].concat();
/// let mesh = TriMesh::new(v, vec![[0, 1, 2], [0, 2, 4], [2, 3, 4], [3, 0, 4]])?;
/// let flipped = flip_caps(&mesh)?;
/// assert_eq!(flipped.triangles(), &[[4, 1, 2], [4, 0, 1], [2, 3, 4], [3, 0, 4]]);
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn flip_caps(mesh: &TriMesh) -> Result<TriMesh> {
    let vertices = mesh.vertices();
    let mut faces = mesh.triangles().to_vec();
    let mut edge_faces = EdgeFaces::new();
    for (f, t) in faces.iter().enumerate() {
        add_face(&mut edge_faces, f, t);
    }
    let mut caps: Vec<usize> = (0..faces.len())
        .filter(|&f| flat_corner(vertices, &faces[f]).is_some())
        .collect();
    for _ in 0..MAX_PASSES {
        let before = caps.len();
        caps.retain(|&f| !flip_cap(vertices, &mut faces, &mut edge_faces, f));
        if caps.len() == before {
            break;
        }
    }
    TriMesh::new(vertices.to_vec(), faces)
}

/// The height over a segment of length `length` below which a point counts as on it:
/// [`CAP_RELATIVE_HEIGHT`] of `length` or of the largest coordinate of `points`.
fn flat_height(length: f64, points: &[[f64; 3]]) -> f64 {
    let magnitude = points
        .iter()
        .flatten()
        .fold(0.0, |m: f64, x| m.max(x.abs()));
    CAP_RELATIVE_HEIGHT * length.max(magnitude)
}

/// The position `k` of the flat corner of `t`, if it has one.
fn flat_corner(vertices: &[[f32; 3]], t: &[u32; 3]) -> Option<usize> {
    (0..3).find(|&k| {
        let at = |i: usize| to_f64(vertices[t[(k + i) % 3] as usize]);
        on_segment(at(0), at(1), at(2))
    })
}

/// True when `b` projects strictly inside segment `ac` and lies on its line.
fn on_segment(b: [f64; 3], a: [f64; 3], c: [f64; 3]) -> bool {
    let edge = sub(c, a);
    let length_squared = dot(edge, edge);
    let along = dot(sub(b, a), edge);
    length_squared > 0.0 && along > 0.0 && along < length_squared && on_line(b, a, c)
}

/// True when `p` lies within the flat tolerance (module docs) of the line through `a` and `c`.
fn on_line(p: [f64; 3], a: [f64; 3], c: [f64; 3]) -> bool {
    let edge = sub(c, a);
    let length = norm(edge);
    norm(cross(edge, sub(p, a))) <= flat_height(length, &[p, a, c]) * length
}

/// Flips the edge opposite the flat corner of face `f` when the conventions allow; true when
/// it did or `f` is no longer a cap.
fn flip_cap(
    vertices: &[[f32; 3]],
    faces: &mut [[u32; 3]],
    edge_faces: &mut EdgeFaces,
    f: usize,
) -> bool {
    let Some(k) = flat_corner(vertices, &faces[f]) else {
        return true;
    };
    let t = faces[f];
    let (b, a, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
    // Exactly two faces on `ac`, running it in opposite directions.
    let [(f0, forward0), (f1, forward1)] = edge_faces[&edge_key(a, c)][..] else {
        return false;
    };
    if forward0 == forward1 {
        return false;
    }
    let neighbour = if f0 == f { f1 } else { f0 };
    let n = faces[neighbour];
    let Some(d) = n.into_iter().find(|&v| v != a && v != c) else {
        return false;
    };
    let at = |v: u32| to_f64(vertices[v as usize]);
    if d == b || on_line(at(d), at(a), at(c)) || edge_faces.contains_key(&edge_key(b, d)) {
        return false;
    }
    remove_face(edge_faces, f, &faces[f]);
    remove_face(edge_faces, neighbour, &n);
    faces[f] = [b, a, d];
    faces[neighbour] = [b, d, c];
    add_face(edge_faces, f, &faces[f]);
    add_face(edge_faces, neighbour, &faces[neighbour]);
    true
}

/// The undirected key of edge `(u, v)`.
pub(crate) fn edge_key(u: u32, v: u32) -> (u32, u32) {
    (u.min(v), u.max(v))
}

pub(crate) fn add_face(edge_faces: &mut EdgeFaces, f: usize, t: &[u32; 3]) {
    for i in 0..3 {
        let (u, v) = (t[i], t[(i + 1) % 3]);
        edge_faces
            .entry(edge_key(u, v))
            .or_default()
            .push((f, u < v));
    }
}

pub(crate) fn remove_face(edge_faces: &mut EdgeFaces, f: usize, t: &[u32; 3]) {
    for i in 0..3 {
        let k = edge_key(t[i], t[(i + 1) % 3]);
        if let Some(list) = edge_faces.get_mut(&k) {
            list.retain(|&(g, _)| g != f);
            if list.is_empty() {
                edge_faces.remove(&k);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{boundary_loops, face_areas, face_normals, is_edge_manifold};

    /// Unit square A B C D over a fan from D and, below its diagonal AC (which holds M1, M2,
    /// M3), face A B C and three caps along the diagonal.
    fn square_with_caps() -> TriMesh {
        let v = vec![
            [0.0, 0.0, 0.0],   // A 0
            [1.0, 0.0, 0.0],   // B 1
            [1.0, 1.0, 0.0],   // C 2
            [0.0, 1.0, 0.0],   // D 3
            [0.25, 0.25, 0.0], // M1 4
            [0.5, 0.5, 0.0],   // M2 5
            [0.75, 0.75, 0.0], // M3 6
        ];
        let fan = [[0, 4, 3], [4, 5, 3], [5, 6, 3], [6, 2, 3]];
        let below = [[0, 1, 2], [0, 2, 5], [5, 2, 6], [0, 5, 4]];
        TriMesh::new(v, fan.into_iter().chain(below).collect()).unwrap()
    }

    #[test]
    fn caps_along_a_crease_are_all_flipped_and_the_surface_stays() {
        let mesh = square_with_caps();
        assert!(face_areas(&mesh).iter().filter(|&&a| a == 0.0).count() == 3);
        let flipped = flip_caps(&mesh).unwrap();
        assert_eq!(flipped.face_count(), mesh.face_count());
        assert!(face_areas(&flipped).iter().all(|&a| a > 0.01));
        let area: f64 = face_areas(&flipped).iter().sum();
        assert!((area - 1.0).abs() < 1e-6);
        assert!(face_normals(&flipped).iter().all(|n| n[2] > 0.99));
        assert!(is_edge_manifold(&flipped));
        let loops = boundary_loops(&flipped);
        assert_eq!((loops.len(), loops[0].len()), (1, 4));
    }

    #[test]
    fn a_cap_on_a_border_or_beside_an_existing_edge_stays() {
        let v = vec![
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
        ];
        // Alone: its long edge has no other face.
        let alone = TriMesh::new(v.clone(), vec![[0, 1, 2]]).unwrap();
        assert_eq!(flip_caps(&alone).unwrap().triangles(), alone.triangles());
        // Its neighbour's far vertex is already joined to the flat corner.
        let joined = TriMesh::new(v, vec![[0, 1, 2], [1, 0, 3], [2, 3, 0]]).unwrap();
        assert_eq!(flip_caps(&joined).unwrap().triangles(), joined.triangles());
    }

    #[test]
    fn a_cap_far_from_the_origin_is_flipped_though_rounding_lifts_it() {
        // Parallelogram A B C D around (1000, 1000) split by AC, with M a third of the way
        // along AC: rounded to f32 (steps of 6·10⁻⁵ here), M lies more than 10⁻⁶ of |AC| off
        // the diagonal, within the rounding of the coordinates.
        let v: Vec<[f32; 3]> = vec![
            [1000.0, 1000.0, 0.0],
            [1003.0, 1000.0, 0.0],
            [1003.0, 1001.0, 0.0],
            [1000.0, 1001.0, 0.0],
            [1001.0, 1000.0 + 1.0 / 3.0, 0.0],
        ];
        let [a, c, m] = [0, 2, 4].map(|i| to_f64(v[i]));
        let height = norm(cross(sub(c, a), sub(m, a))) / norm(sub(c, a));
        assert!(height > CAP_RELATIVE_HEIGHT * norm(sub(c, a)), "{height:e}");
        let faces = vec![[0, 1, 2], [0, 2, 4], [0, 4, 3], [4, 2, 3]];
        let flipped = flip_caps(&TriMesh::new(v, faces).unwrap()).unwrap();
        let areas = face_areas(&flipped);
        assert!(areas.iter().all(|&a| a > 0.1), "{areas:?}");
        assert!((areas.iter().sum::<f64>() - 3.0).abs() < 1e-3);
    }

    #[test]
    fn an_obtuse_face_with_area_is_no_cap() {
        // The corner at (1, 0.01) lies 1 % of the edge's length off it.
        let v = vec![
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [1.0, 0.01, 0.0],
            [1.0, -1.0, 0.0],
        ];
        let mesh = TriMesh::new(v, vec![[0, 1, 2], [1, 0, 3]]).unwrap();
        assert_eq!(flip_caps(&mesh).unwrap().triangles(), mesh.triangles());
    }
}
