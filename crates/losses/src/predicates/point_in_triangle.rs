//! Is a point inside a triangle, by areas? The overlap test of thesis eq. 6.13.

use crate::predicates::orient3d::widen;
use meshgnn_geometry::vec3::{cross, dot, sub};

/// Tolerances of [`point_in_triangle`], relative to the triangle's size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InsideTolerance {
    /// Allowed relative excess of `A₁ + A₂ + A₃` over the triangle's area `A`.
    pub area: f64,
    /// Allowed distance from the triangle's plane, as a fraction of `sqrt(A)` — the thesis'
    /// "slightly increased tolerance along the axis normal to the triangle", so that a point
    /// of a parallel, nearly coplanar triangle still counts as overlapping.
    pub normal: f64,
}

impl Default for InsideTolerance {
    fn default() -> Self {
        Self {
            area: 1e-6,
            normal: 1e-3,
        }
    }
}

/// Area of triangle `(a, b, c)` in `f64`.
fn area(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    let n = cross(sub(b, a), sub(c, a));
    0.5 * dot(n, n).sqrt()
}

/// Ch. 6.3.4 overlap test: `p` belongs to triangle `t: 3×3` when its distance to the
/// triangle's plane is at most `tol.normal · sqrt(A)` and, after projecting it onto the plane,
/// the three areas `A_i` obtained by substituting each vertex with `p` sum to `A` within
/// `tol.area · A`. Degenerate triangles (zero area) contain nothing. Points on the boundary
/// count as inside.
///
/// ```
/// use meshgnn_losses::predicates::{point_in_triangle, InsideTolerance};
/// let t = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
/// let tol = InsideTolerance::default();
/// assert!(point_in_triangle(&[0.25, 0.25, 0.0], &t, tol));
/// assert!(point_in_triangle(&[0.25, 0.25, 1e-4], &t, tol)); // within the normal tolerance
/// assert!(!point_in_triangle(&[0.25, 0.25, 0.1], &t, tol));
/// assert!(!point_in_triangle(&[0.75, 0.75, 0.0], &t, tol));
/// ```
pub fn point_in_triangle(p: &[f32; 3], t: &[[f32; 3]; 3], tol: InsideTolerance) -> bool {
    let [a, b, c] = t.map(|v| widen(&v));
    let p = widen(p);
    let n = cross(sub(b, a), sub(c, a));
    let nn = dot(n, n);
    let whole = 0.5 * nn.sqrt();
    if whole.is_nan() || whole <= 0.0 {
        return false;
    }
    let offset = dot(sub(p, a), n) / nn.sqrt();
    if offset.abs() > tol.normal * whole.sqrt() {
        return false;
    }
    let s = offset / nn.sqrt();
    let projected = [p[0] - s * n[0], p[1] - s * n[1], p[2] - s * n[2]];
    let parts = area(projected, b, c) + area(a, projected, c) + area(a, b, projected);
    parts - whole <= tol.area * whole
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vertices_edges_and_outside() {
        let t = [[0.0, 0.0, 1.0], [2.0, 0.0, 1.0], [0.0, 2.0, 1.0]];
        let tol = InsideTolerance::default();
        assert!(point_in_triangle(&[0.0, 0.0, 1.0], &t, tol));
        assert!(point_in_triangle(&[1.0, 1.0, 1.0], &t, tol)); // on the hypotenuse
        assert!(!point_in_triangle(&[1.01, 1.01, 1.0], &t, tol));
        assert!(!point_in_triangle(&[-0.01, 0.5, 1.0], &t, tol));
        let flat = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
        assert!(!point_in_triangle(&[1.0, 0.0, 0.0], &flat, tol));
    }
}
