//! A triangulated torus: the closed genus-one test shape (a ring, a curled part).

use crate::TriMesh;

/// The torus of radii `major` (centre to tube axis) and `minor` (the tube) around the z axis,
/// centred at the origin: `around × across` vertices, `index = i·across + j` for step `i` around
/// the axis and step `j` around the tube (from the outer equator, towards `+z`), two outward
/// triangles per cell. Closed, edge-manifold, Euler characteristic 0.
///
/// ```
/// let ring = meshgnn_geometry::torus(2.0, 0.5, 16, 8);
/// assert_eq!((ring.vertex_count(), ring.face_count()), (128, 256));
/// assert!(meshgnn_geometry::is_watertight(&ring));
/// assert_eq!(ring.vertices()[0], [2.5, 0.0, 0.0]);
/// ```
pub fn torus(major: f32, minor: f32, around: u32, across: u32) -> TriMesh {
    let (around, across) = (around.max(3), across.max(3));
    let vertices = (0..around)
        .flat_map(|i| (0..across).map(move |j| (i, j)))
        .map(|(i, j)| {
            let u = std::f32::consts::TAU * i as f32 / around as f32;
            let v = std::f32::consts::TAU * j as f32 / across as f32;
            let r = major + minor * v.cos();
            [r * u.cos(), r * u.sin(), minor * v.sin()]
        })
        .collect();
    let at = |i: u32, j: u32| (i % around) * across + j % across;
    let triangles = (0..around)
        .flat_map(|i| (0..across).map(move |j| (i, j)))
        .flat_map(|(i, j)| {
            [
                [at(i, j), at(i + 1, j), at(i + 1, j + 1)],
                [at(i, j), at(i + 1, j + 1), at(i, j + 1)],
            ]
        })
        .collect();
    TriMesh::new(vertices, triangles).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{is_edge_manifold, is_watertight};

    #[test]
    fn closed_genus_one_outward_with_the_analytic_volume() {
        let (major, minor) = (3.0f64, 1.0f64);
        let ring = torus(major as f32, minor as f32, 96, 48);
        assert!(is_watertight(&ring) && is_edge_manifold(&ring));
        // V − E + F = 0 for genus one (E = 3F/2 on a closed surface).
        let (v, f) = (ring.vertex_count() as i64, ring.face_count() as i64);
        assert_eq!(v - 3 * f / 2 + f, 0);
        // Signed volume by the divergence theorem: positive (outward), near 2π²Rr².
        let volume: f64 = ring
            .triangles()
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|k| ring.vertices()[k as usize].map(f64::from));
                (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                    + a[2] * (b[0] * c[1] - b[1] * c[0]))
                    / 6.0
            })
            .sum();
        let exact = 2.0 * std::f64::consts::PI.powi(2) * major * minor * minor;
        assert!((volume - exact).abs() < 0.01 * exact, "{volume} vs {exact}");
    }

    #[test]
    fn fewer_than_three_steps_are_raised_to_three() {
        let ring = torus(1.0, 0.2, 1, 0);
        assert_eq!(ring.vertex_count(), 9);
        assert!(is_watertight(&ring));
    }
}
