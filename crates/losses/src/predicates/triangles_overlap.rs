//! Does a triangle overlap another? Counts toward `m_o(t)` of thesis eq. 6.13.

use crate::predicates::point_in_triangle::{InsideTolerance, point_in_triangle};
use crate::predicates::triangle_lattice::barycentric_point;

/// True when at least one of the interior sample points of `t` (barycentric `lattice`, e.g.
/// `triangle_lattice(10)`, the thesis' 100 points) lies in `u` by the area test
/// [`super::point_in_triangle`]. Samples are strictly interior, so a neighbour that only shares
/// an edge or vertex with `t` (coplanar or folded) does not overlap it.
///
/// ```
/// use meshgnn_losses::predicates::{triangles_overlap, triangle_lattice, InsideTolerance};
/// let lattice = triangle_lattice(10);
/// let tol = InsideTolerance::default();
/// let t = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]];
/// let over = [[0.5, 0.5, 0.0], [2.5, 0.5, 0.0], [0.5, 2.5, 0.0]];
/// let beside = [[2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [2.0, 2.0, 0.0]]; // shares an edge
/// assert!(triangles_overlap(&t, &over, &lattice, tol));
/// assert!(!triangles_overlap(&t, &beside, &lattice, tol));
/// ```
pub fn triangles_overlap(
    t: &[[f32; 3]; 3],
    u: &[[f32; 3]; 3],
    lattice: &[[f32; 3]],
    tol: InsideTolerance,
) -> bool {
    lattice
        .iter()
        .any(|w| point_in_triangle(&barycentric_point(t, w), u, tol))
}
