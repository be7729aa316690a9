//! Folded faces flipped away: in a consistently oriented face set, a face that faces against
//! the reference normals of its corners while its neighbours face along theirs is folded back
//! over them (the neural mesh simplifier of thesis ch. 6 connects kept vertices whose
//! triangle overlaps its neighbour). Its orientation cannot be mended without breaking the
//! consistency ([`crate::select_manifold_faces`]); the fold is in the connectivity, so an edge
//! flip mends it.
//!
//! Face `(a, b, d)` and the face across `ab`, `(b, a, c)`, become `(a, c, d)` and `(c, b, d)`:
//! the quadrilateral's outline, the border and the orientation stay. A flip is made only when
//! `cd` is not an edge yet and both new faces face along their corners' reference normals;
//! of the folded face's edges that allow one, the flip whose worse new face faces them best is
//! made. Passes over the folds left repeat while one flips, at most [`MAX_PASSES`].

use crate::cap_flips::{EdgeFaces, add_face, edge_key, remove_face};
use crate::error::{Error, Result};
use crate::manifold_face_selection::reference_normal;
use crate::tri_mesh::TriMesh;
use crate::vec3::{dot, norm, triangle_cross};

/// Passes over the folds at most.
const MAX_PASSES: usize = 8;

/// `mesh` with its folded faces flipped away (module docs); vertices unchanged, faces in the
/// same order with each flipped pair rewritten in place. `reference_normals` has one normal
/// per vertex (the input's at the vertex each stands for).
///
/// ```
/// use meshgnn_geometry::{TriMesh, flip_folds};
/// // A dart 0 1 2 3 (1 its reflex corner) split along 0-2, outside it: face (0, 1, 2) is
/// // folded under (0, 2, 3) and faces −z; flipping 0-2 to 1-3 gives two faces along +z.
/// let v = vec![[0.0, 0.0, 0.0], [1.0, 0.5, 0.0], [2.0, 0.0, 0.0], [1.0, 2.0, 0.0]];
/// let mesh = TriMesh::new(v, vec![[0, 1, 2], [0, 2, 3]])?;
/// let flipped = flip_folds(&mesh, &[[0.0, 0.0, 1.0]; 4])?;
/// assert_eq!(flipped.triangles(), &[[2, 3, 1], [3, 0, 1]]);
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn flip_folds(mesh: &TriMesh, reference_normals: &[[f32; 3]]) -> Result<TriMesh> {
    let vertices = mesh.vertices();
    if reference_normals.len() != vertices.len() {
        return Err(Error::LengthMismatch {
            what: "reference normals",
            expected: vertices.len(),
            actual: reference_normals.len(),
        });
    }
    let mut faces = mesh.triangles().to_vec();
    let mut edge_faces = EdgeFaces::new();
    for (f, t) in faces.iter().enumerate() {
        add_face(&mut edge_faces, f, t);
    }
    let facing = |t: [u32; 3]| facing_reference(vertices, reference_normals, t);
    let mut folds: Vec<usize> = (0..faces.len())
        .filter(|&f| facing(faces[f]) < 0.0)
        .collect();
    for _ in 0..MAX_PASSES {
        let before = folds.len();
        folds.retain(|&f| !flip_fold(&mut faces, &mut edge_faces, f, &facing));
        if folds.len() == before {
            break;
        }
    }
    TriMesh::new(vertices.to_vec(), faces)
}

/// The cosine between `t`'s normal and the sum of its corners' reference normals (0 for a
/// face without area or a reference that cancels out).
fn facing_reference(vertices: &[[f32; 3]], normals: &[[f32; 3]], t: [u32; 3]) -> f64 {
    let normal = triangle_cross(t.map(|v| vertices[v as usize]));
    let reference = reference_normal(normals, t);
    let scale = norm(normal) * norm(reference);
    if scale > 0.0 {
        dot(normal, reference) / scale
    } else {
        0.0
    }
}

/// Flips the best edge of the folded face `f` (module docs); true when it did or `f` no
/// longer faces against its reference.
fn flip_fold(
    faces: &mut [[u32; 3]],
    edge_faces: &mut EdgeFaces,
    f: usize,
    facing: &impl Fn([u32; 3]) -> f64,
) -> bool {
    let t = faces[f];
    if facing(t) >= 0.0 {
        return true;
    }
    let mut best: Option<(f64, usize, [u32; 3], [u32; 3])> = None;
    for k in 0..3 {
        let (a, b, d) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
        // Exactly two faces on `ab`, the other running it from `b` to `a`.
        let [(f0, forward0), (f1, forward1)] = edge_faces[&edge_key(a, b)][..] else {
            continue;
        };
        if forward0 == forward1 {
            continue;
        }
        let neighbour = if f0 == f { f1 } else { f0 };
        let Some(c) = faces[neighbour].into_iter().find(|&v| v != a && v != b) else {
            continue;
        };
        if c == d || edge_faces.contains_key(&edge_key(c, d)) {
            continue;
        }
        let (first, second) = ([a, c, d], [c, b, d]);
        let worse = facing(first).min(facing(second));
        if worse > 0.0 && best.is_none_or(|(w, ..)| worse > w) {
            best = Some((worse, neighbour, first, second));
        }
    }
    let Some((_, neighbour, first, second)) = best else {
        return false;
    };
    remove_face(edge_faces, f, &t);
    remove_face(edge_faces, neighbour, &faces[neighbour]);
    faces[f] = first;
    faces[neighbour] = second;
    add_face(edge_faces, f, &first);
    add_face(edge_faces, neighbour, &second);
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{boundary_loops, is_edge_manifold, mesh_report};

    /// A 3 × 3 grid of unit cells in z = 0 (vertices `4 j + i`), each cell split along its
    /// diagonal from the lower left corner, with vertex 5 moved across the diagonal 1-6 of
    /// the cell to its right: face (1, 6, 5), consistent with its neighbours, is folded
    /// under them and faces −z.
    fn grid_with_a_fold() -> TriMesh {
        let mut v: Vec<[f32; 3]> = (0..16)
            .map(|i| [(i % 4) as f32, (i / 4) as f32, 0.0])
            .collect();
        v[5] = [1.8, 0.5, 0.0];
        let mut faces = Vec::new();
        for j in 0..3u32 {
            for i in 0..3u32 {
                let c = 4 * j + i;
                faces.push([c, c + 1, c + 5]);
                faces.push([c, c + 5, c + 4]);
            }
        }
        TriMesh::new(v, faces).unwrap()
    }

    #[test]
    fn a_fold_in_a_grid_is_flipped_away_and_the_outline_stays() {
        let mesh = grid_with_a_fold();
        let up = vec![[0.0, 0.0, 1.0]; 16];
        let facing = |m: &TriMesh| -> Vec<f64> {
            m.triangles()
                .iter()
                .map(|&t| facing_reference(m.vertices(), &up, t))
                .collect()
        };
        assert_eq!(mesh_report(&mesh).misoriented_edges, 0);
        assert_eq!(facing(&mesh).iter().filter(|&&c| c < 0.0).count(), 1);
        let flipped = flip_folds(&mesh, &up).unwrap();
        assert!(facing(&flipped).iter().all(|&c| c > 0.0), "{flipped:?}");
        assert_eq!(mesh_report(&flipped).misoriented_edges, 0);
        assert!(is_edge_manifold(&flipped));
        assert_eq!(flipped.face_count(), mesh.face_count());
        assert_eq!(boundary_loops(&flipped), boundary_loops(&mesh));
    }

    #[test]
    fn faces_along_their_references_and_unflippable_folds_stay() {
        // A lone face against its reference has no neighbour to flip with.
        let v = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let lone = TriMesh::new(v, vec![[0, 2, 1]]).unwrap();
        let up = [[0.0, 0.0, 1.0]; 3];
        assert_eq!(flip_folds(&lone, &up).unwrap(), lone);
        let grid = crate::grid_plane(3, 3);
        let up = vec![[0.0, 0.0, 1.0]; grid.vertex_count()];
        assert_eq!(flip_folds(&grid, &up).unwrap(), grid);
        assert!(flip_folds(&grid, &up[1..]).is_err());
    }
}
