//! Connected components of a mesh's surface.
//!
//! # Conventions
//! Vertex-based: two vertices are connected when a face contains both (faces touching at a
//! single vertex join), so the labels partition the vertices and line up with per-vertex
//! signals such as Laplacian eigenvectors. Unreferenced vertices belong to no component and
//! are labelled [`UNREFERENCED`]. Components are numbered `0..count` in order of their
//! smallest vertex index (deterministic). Union-find from petgraph, O(F α(V)).

use petgraph::unionfind::UnionFind;

use crate::TriMesh;

/// Label of a vertex that no face uses.
pub const UNREFERENCED: u32 = u32::MAX;

/// `(count, labels: #V)`: the number of components and each vertex's component.
///
/// ```
/// use meshgnn_geometry::{TriMesh, connected_components, UNREFERENCED};
/// let v = vec![[0.0; 3]; 7];
/// let mesh = TriMesh::new(v, vec![[4, 5, 6], [0, 1, 2]])?;
/// let (count, labels) = connected_components(&mesh);
/// assert_eq!(count, 2);
/// assert_eq!(labels, vec![0, 0, 0, UNREFERENCED, 1, 1, 1]);
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn connected_components(mesh: &TriMesh) -> (usize, Vec<u32>) {
    let n = mesh.vertex_count();
    let mut sets = UnionFind::<u32>::new(n);
    let mut referenced = vec![false; n];
    for &[a, b, c] in mesh.triangles() {
        sets.union(a, b);
        sets.union(a, c);
        referenced[a as usize] = true;
        referenced[b as usize] = true;
        referenced[c as usize] = true;
    }
    let roots = sets.into_labeling();
    let mut label_of_root = vec![UNREFERENCED; n];
    let mut count = 0u32;
    let labels = (0..n)
        .map(|v| {
            if !referenced[v] {
                return UNREFERENCED;
            }
            let root = roots[v] as usize;
            if label_of_root[root] == UNREFERENCED {
                label_of_root[root] = count;
                count += 1;
            }
            label_of_root[root]
        })
        .collect();
    (count as usize, labels)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{icosphere, subdivided_cube};

    #[test]
    fn two_disjoint_spheres_are_two_components() {
        let (mut v, mut f, ..) = icosphere(2).into_parts();
        let offset = v.len() as u32;
        let shifted: Vec<_> = v.iter().map(|p| [p[0] + 3.0, p[1], p[2]]).collect();
        let faces: Vec<_> = f.iter().map(|t| t.map(|i| i + offset)).collect();
        v.extend(shifted);
        f.extend(faces);
        let (count, labels) = connected_components(&TriMesh::new(v, f).unwrap());
        assert_eq!(count, 2);
        assert!(labels[..offset as usize].iter().all(|&l| l == 0));
        assert!(labels[offset as usize..].iter().all(|&l| l == 1));
        assert_eq!(connected_components(&subdivided_cube(3)).0, 1);
    }
}
