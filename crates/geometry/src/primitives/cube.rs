//! A closed cube whose faces are regular grids.

use std::collections::HashMap;

use crate::TriMesh;

/// The cube `[-1, 1]³` with each face cut into `n × n` cells of two triangles, vertices shared
/// along edges and corners (closed, manifold, `6n²+2` vertices, `12n²` triangles),
/// counter-clockwise seen from outside. Its face normals are exactly the axis directions.
///
/// ```
/// let cube = meshgnn_geometry::subdivided_cube(3);
/// assert_eq!((cube.vertex_count(), cube.face_count()), (56, 108));
/// ```
pub fn subdivided_cube(n: u32) -> TriMesh {
    let n = n.max(1);
    let mut index_of: HashMap<[u32; 3], u32> = HashMap::new();
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    // Lattice coordinates in 0..=n per axis; position = 2·c/n − 1, so shared points weld exactly.
    let mut vertex = |lattice: [u32; 3], vertices: &mut Vec<[f32; 3]>| -> u32 {
        *index_of.entry(lattice).or_insert_with(|| {
            vertices.push(lattice.map(|c| 2.0 * c as f32 / n as f32 - 1.0));
            (vertices.len() - 1) as u32
        })
    };
    // For the normal axis `a`, (u, v) are chosen so that u × v = +a.
    for (a, u, v) in [(0, 1, 2), (1, 2, 0), (2, 0, 1)] {
        for side in [0, n] {
            for i in 0..n {
                for j in 0..n {
                    let corner = |di: u32, dj: u32| {
                        let mut lattice = [0; 3];
                        lattice[a] = side;
                        lattice[u] = i + di;
                        lattice[v] = j + dj;
                        lattice
                    };
                    let q = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)]
                        .map(|c| vertex(c, &mut vertices));
                    if side == n {
                        triangles.extend([[q[0], q[1], q[2]], [q[0], q[2], q[3]]]);
                    } else {
                        triangles.extend([[q[0], q[2], q[1]], [q[0], q[3], q[2]]]);
                    }
                }
            }
        }
    }
    TriMesh::new(vertices, triangles).unwrap_or_default()
}
