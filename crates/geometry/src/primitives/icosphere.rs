//! The icosphere: a regular icosahedron subdivided `n` times and projected onto the unit sphere.

use std::collections::HashMap;

use crate::TriMesh;

/// A unit sphere centred at the origin: the icosahedron with each triangle split into four,
/// `subdivisions` times, new vertices projected onto the sphere. `10·4ⁿ + 2` vertices and
/// `20·4ⁿ` triangles, counter-clockwise seen from outside, closed and manifold.
///
/// ```
/// let sphere = meshgnn_geometry::icosphere(2);
/// assert_eq!((sphere.vertex_count(), sphere.face_count()), (162, 320));
/// ```
pub fn icosphere(subdivisions: u32) -> TriMesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut vertices: Vec<[f64; 3]> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .into_iter()
    .map(normalized)
    .collect();
    let mut triangles: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut midpoints = HashMap::with_capacity(triangles.len() * 3 / 2);
        let mut midpoint = |a: u32, b: u32, vertices: &mut Vec<[f64; 3]>| -> u32 {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let (p, q) = (vertices[a as usize], vertices[b as usize]);
                vertices.push(normalized([p[0] + q[0], p[1] + q[1], p[2] + q[2]]));
                (vertices.len() - 1) as u32
            })
        };
        triangles = triangles
            .iter()
            .flat_map(|&[a, b, c]| {
                let ab = midpoint(a, b, &mut vertices);
                let bc = midpoint(b, c, &mut vertices);
                let ca = midpoint(c, a, &mut vertices);
                [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
            })
            .collect();
    }
    let vertices = vertices.into_iter().map(|p| p.map(|x| x as f32)).collect();
    TriMesh::new(vertices, triangles).unwrap_or_default()
}

fn normalized(p: [f64; 3]) -> [f64; 3] {
    let norm = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
    p.map(|x| x / norm)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vertices_lie_on_the_unit_sphere_and_faces_point_outwards() {
        let sphere = icosphere(3);
        assert_eq!(sphere.vertex_count(), 642);
        for p in sphere.vertices() {
            let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            assert!((r - 1.0).abs() < 1e-6);
        }
        for f in 0..sphere.face_count() {
            let [a, b, c] = sphere.triangle_positions(f);
            let (u, v) = (sub(b, a), sub(c, a));
            let n = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            let centroid_dot = (0..3).map(|i| n[i] * (a[i] + b[i] + c[i])).sum::<f32>();
            assert!(centroid_dot > 0.0, "face {f} points inwards");
        }
    }

    fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
        [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
    }
}
