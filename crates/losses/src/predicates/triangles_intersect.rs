//! Do two triangles penetrate each other? Counts toward `m_c(t)` of thesis eq. 6.11.

use crate::predicates::segment_triangle::segment_crosses_triangle;

/// True when an edge of `t` properly pierces the interior of `u` or an edge of `u` pierces
/// `t` (see [`super::segment_crosses_triangle`]). Neighbours sharing an edge or a vertex
/// touch but do not penetrate and return false; coplanar overlaps are left to
/// [`super::edge_crossing_count`] and [`super::triangles_overlap`].
///
/// ```
/// use meshgnn_losses::predicates::triangles_intersect;
/// let t = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]];
/// let u = [[0.5, 0.5, -1.0], [0.5, 0.5, 1.0], [3.0, 3.0, 0.5]]; // stabs through t
/// assert!(triangles_intersect(&t, &u));
/// let far = [[0.0, 0.0, 5.0], [1.0, 0.0, 5.0], [0.0, 1.0, 5.0]];
/// assert!(!triangles_intersect(&t, &far));
/// ```
pub fn triangles_intersect(t: &[[f32; 3]; 3], u: &[[f32; 3]; 3]) -> bool {
    let pierces = |a: &[[f32; 3]; 3], b: &[[f32; 3]; 3]| {
        (0..3).any(|k| segment_crosses_triangle(&a[k], &a[(k + 1) % 3], b))
    };
    pierces(t, u) || pierces(u, t)
}
