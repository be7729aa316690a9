//! Duplicate faces: the same three vertices as an earlier face, in any order or orientation.
//! They double-count area and make edges look non-manifold; a common artefact of merged scans.

use rayon::prelude::*;

use crate::TriMesh;

/// Number of faces whose sorted vertex triple equals that of an earlier face (so `m` copies of
/// a face count `m − 1`). Sort-based, O(F log F).
///
/// ```
/// use meshgnn_geometry::{TriMesh, duplicate_faces};
/// let v = vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
/// let mesh = TriMesh::new(v, vec![[0, 1, 2], [2, 1, 0], [1, 2, 0]])?;
/// assert_eq!(duplicate_faces(&mesh), 2);
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn duplicate_faces(mesh: &TriMesh) -> usize {
    let mut keys: Vec<u128> = mesh
        .triangles()
        .par_iter()
        .map(|t| {
            let mut s = *t;
            s.sort_unstable();
            (u128::from(s[0]) << 64) | (u128::from(s[1]) << 32) | u128::from(s[2])
        })
        .collect();
    keys.par_sort_unstable();
    keys.windows(2).filter(|w| w[0] == w[1]).count()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::icosphere;

    #[test]
    fn a_clean_mesh_has_none_and_a_copied_face_is_found() {
        let (v, mut f, ..) = icosphere(2).into_parts();
        assert_eq!(
            duplicate_faces(&TriMesh::new(v.clone(), f.clone()).unwrap()),
            0
        );
        f.push(f[17]);
        assert_eq!(duplicate_faces(&TriMesh::new(v, f).unwrap()), 1);
    }
}
