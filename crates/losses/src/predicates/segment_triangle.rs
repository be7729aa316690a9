//! Does a segment pierce a triangle? The collision test of thesis eq. 6.11.

use crate::predicates::orient3d::{orient3d, widen};

/// True when the segment `p–q` crosses the interior of triangle `t: 3×3` properly: `p` and
/// `q` lie strictly on opposite sides of the triangle's plane and the crossing point lies
/// strictly inside the triangle (all three edge orientations agree, none zero).
///
/// Touching is not crossing: a segment with an endpoint on the plane (for example an edge
/// that shares a vertex with the triangle, as between neighbouring faces of a mesh) or one
/// passing exactly through an edge or vertex of the triangle returns false, and so does a
/// segment lying in the plane (see [`super::segments_cross`] for the coplanar case).
/// Degenerate (zero-area) triangles are never pierced.
///
/// ```
/// use meshgnn_losses::predicates::segment_crosses_triangle;
/// let t = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
/// assert!(segment_crosses_triangle(&[0.2, 0.2, -1.0], &[0.2, 0.2, 1.0], &t));
/// assert!(!segment_crosses_triangle(&[0.9, 0.9, -1.0], &[0.9, 0.9, 1.0], &t));
/// assert!(!segment_crosses_triangle(&[0.0, 0.0, 0.0], &[0.2, 0.2, 1.0], &t)); // shares a vertex
/// ```
pub fn segment_crosses_triangle(p: &[f32; 3], q: &[f32; 3], t: &[[f32; 3]; 3]) -> bool {
    let (p, q) = (widen(p), widen(q));
    let [a, b, c] = t.map(|v| widen(&v));
    let sp = orient3d(a, b, c, p);
    let sq = orient3d(a, b, c, q);
    if sp == 0 || sq == 0 || sp == sq {
        return false;
    }
    // The line p→q passes inside when it sees the three edges with the same orientation.
    let e1 = orient3d(p, q, a, b);
    let e2 = orient3d(p, q, b, c);
    let e3 = orient3d(p, q, c, a);
    e1 != 0 && e1 == e2 && e2 == e3
}

#[cfg(test)]
mod tests {
    use super::*;

    const T: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

    #[test]
    fn crossing_and_missing() {
        assert!(segment_crosses_triangle(
            &[0.3, 0.3, 1.0],
            &[0.3, 0.3, -1.0],
            &T
        ));
        assert!(!segment_crosses_triangle(
            &[0.3, 0.3, 1.0],
            &[0.3, 0.3, 0.5],
            &T
        )); // same side
        assert!(!segment_crosses_triangle(
            &[2.0, 2.0, 1.0],
            &[2.0, 2.0, -1.0],
            &T
        )); // outside
        // q = (1,1,0) lies in the plane, outside the triangle: touching, not crossing
        assert!(!segment_crosses_triangle(
            &[0.0, 0.0, 1.0],
            &[1.0, 1.0, 0.0],
            &T
        ));
    }

    #[test]
    fn touching_edge_is_not_crossing() {
        // passes through the middle of edge (a, b)
        assert!(!segment_crosses_triangle(
            &[0.5, 0.0, 1.0],
            &[0.5, 0.0, -1.0],
            &T
        ));
        // lies in the plane
        assert!(!segment_crosses_triangle(
            &[-1.0, 0.2, 0.0],
            &[2.0, 0.2, 0.0],
            &T
        ));
    }

    #[test]
    fn degenerate_triangle_is_never_pierced() {
        let flat = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
        assert!(!segment_crosses_triangle(
            &[0.5, 0.0, 1.0],
            &[0.5, 0.0, -1.0],
            &flat
        ));
    }
}
