//! A regular triangulated grid on the unit square.

use crate::TriMesh;

/// The unit square `[0, 1]²` in the plane `z = 0`, cut into `nx × ny` cells of two triangles
/// each; `(nx + 1)(ny + 1)` vertices, row-major from the origin (`index = j·(nx + 1) + i`),
/// counter-clockwise seen from `+z`. An open disk with one boundary loop.
///
/// ```
/// let plane = meshgnn_geometry::grid_plane(4, 3);
/// assert_eq!((plane.vertex_count(), plane.face_count()), (20, 24));
/// assert_eq!(plane.vertices()[6], [0.25, 1.0 / 3.0, 0.0]);
/// ```
pub fn grid_plane(nx: u32, ny: u32) -> TriMesh {
    let (nx, ny) = (nx.max(1), ny.max(1));
    let vertices = (0..=ny)
        .flat_map(|j| (0..=nx).map(move |i| [i as f32 / nx as f32, j as f32 / ny as f32, 0.0]))
        .collect();
    let index = |i: u32, j: u32| j * (nx + 1) + i;
    let triangles = (0..ny)
        .flat_map(|j| (0..nx).map(move |i| (i, j)))
        .flat_map(|(i, j)| {
            let (a, b, c, d) = (
                index(i, j),
                index(i + 1, j),
                index(i + 1, j + 1),
                index(i, j + 1),
            );
            [[a, b, c], [a, c, d]]
        })
        .collect();
    TriMesh::new(vertices, triangles).unwrap_or_default()
}
