//! Degenerate faces: a repeated vertex index, or (numerically) zero area.
//!
//! # Conventions
//! A face with distinct indices is degenerate when its height is below `1e-10` times its
//! longest edge, i.e. `|(b − a) × (c − a)| ≤ 1e-10 · max_edge²` (computed in `f64`), so the
//! test does not depend on the mesh's scale. Such faces have no normal and make cotangent
//! weights infinite; [`crate::TriMesh::without_degenerate_faces`] drops index-degenerate ones.

use rayon::prelude::*;

use crate::TriMesh;
use crate::vec3::{dot, norm, sub, to_f64, triangle_cross};

/// Relative height below which a triangle counts as zero-area.
const RELATIVE_HEIGHT: f64 = 1e-10;

/// True when triangle `corners` (`3×3` positions) has zero area relative to its size.
pub(crate) fn is_zero_area(corners: [[f32; 3]; 3]) -> bool {
    let [a, b, c] = corners.map(to_f64);
    let longest = [sub(b, a), sub(c, b), sub(a, c)]
        .into_iter()
        .map(|e| dot(e, e))
        .fold(0.0, f64::max);
    norm(triangle_cross(corners)) <= RELATIVE_HEIGHT * longest
}

/// Number of degenerate faces: a repeated vertex index or zero area (see the conventions).
/// Duplicate faces are counted separately by [`crate::duplicate_faces`].
///
/// ```
/// use meshgnn_geometry::{TriMesh, degenerate_faces};
/// let v = vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [2.0, 0.0, 0.0]];
/// let mesh = TriMesh::new(v, vec![[0, 1, 2], [0, 0, 2], [0, 1, 3]])?;
/// assert_eq!(degenerate_faces(&mesh), 2);
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn degenerate_faces(mesh: &TriMesh) -> usize {
    let vertices = mesh.vertices();
    mesh.triangles()
        .par_iter()
        .filter(|t| {
            t[0] == t[1]
                || t[1] == t[2]
                || t[0] == t[2]
                || is_zero_area(t.map(|v| vertices[v as usize]))
        })
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::icosphere;

    #[test]
    fn tiny_but_proper_triangles_are_not_degenerate() {
        let scale = 1e-6f32;
        let v = vec![[0.0; 3], [scale, 0.0, 0.0], [0.0, scale, 0.0]];
        let mesh = TriMesh::new(v, vec![[0, 1, 2]]).unwrap();
        assert_eq!(degenerate_faces(&mesh), 0);
        assert_eq!(degenerate_faces(&icosphere(3)), 0);
    }
}
