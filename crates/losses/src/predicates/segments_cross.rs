//! Do two segments cross in 3-d? The edge-crossing test of thesis eq. 6.12.

use crate::predicates::orient3d::{orient3d, widen};
use meshgnn_geometry::vec3::{cross, sub};

/// 2-d orientation of `(a, b, c)` after dropping coordinate `drop`.
fn orient2d_dropping(a: [f64; 3], b: [f64; 3], c: [f64; 3], drop: usize) -> i8 {
    let (i, j) = match drop {
        0 => (1, 2),
        1 => (2, 0),
        _ => (0, 1),
    };
    let det = (b[i] - a[i]) * (c[j] - a[j]) - (b[j] - a[j]) * (c[i] - a[i]);
    let bound = 4.0
        * f64::EPSILON
        * ((b[i] - a[i]).abs() * (c[j] - a[j]).abs() + (b[j] - a[j]).abs() * (c[i] - a[i]).abs());
    if det > bound {
        1
    } else if det < -bound {
        -1
    } else {
        0
    }
}

/// True when segments `p1–p2` and `q1–q2` are coplanar (by [`orient3d`], within its rounding
/// bound) and cross properly: each segment's endpoints lie strictly on opposite sides of the
/// other's line. Shared endpoints, an endpoint touching the other segment, collinear overlap
/// and identical segments (the shared edge of neighbouring faces) are not crossings. Skew
/// segments never cross.
///
/// ```
/// use meshgnn_losses::predicates::segments_cross;
/// let (a, b) = ([0.0, 0.0, 1.0], [2.0, 2.0, 1.0]);
/// assert!(segments_cross(&a, &b, &[0.0, 2.0, 1.0], &[2.0, 0.0, 1.0]));
/// assert!(!segments_cross(&a, &b, &[0.0, 2.0, 1.5], &[2.0, 0.0, 0.0])); // skew
/// assert!(!segments_cross(&a, &b, &a, &[2.0, 0.0, 1.0])); // shared endpoint
/// ```
pub fn segments_cross(p1: &[f32; 3], p2: &[f32; 3], q1: &[f32; 3], q2: &[f32; 3]) -> bool {
    let [p1, p2, q1, q2] = [p1, p2, q1, q2].map(widen);
    if orient3d(p1, p2, q1, q2) != 0 {
        return false;
    }
    let n = cross(sub(p2, p1), sub(q2, q1));
    let n = if n.iter().all(|c| *c == 0.0) {
        // parallel (or degenerate) segments: no proper crossing
        return false;
    } else {
        n
    };
    let drop = if n[0].abs() >= n[1].abs() && n[0].abs() >= n[2].abs() {
        0
    } else if n[1].abs() >= n[2].abs() {
        1
    } else {
        2
    };
    let a = orient2d_dropping(p1, p2, q1, drop);
    let b = orient2d_dropping(p1, p2, q2, drop);
    let c = orient2d_dropping(q1, q2, p1, drop);
    let d = orient2d_dropping(q1, q2, p2, drop);
    a != 0 && b != 0 && c != 0 && d != 0 && a != b && c != d
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crossing_in_every_axis_plane() {
        for axis in 0..3 {
            let put = |u: f32, v: f32| -> [f32; 3] {
                let mut p = [0.5f32; 3];
                p[(axis + 1) % 3] = u;
                p[(axis + 2) % 3] = v;
                p
            };
            assert!(segments_cross(
                &put(0.0, 0.0),
                &put(1.0, 1.0),
                &put(0.0, 1.0),
                &put(1.0, 0.0)
            ));
            assert!(!segments_cross(
                &put(0.0, 0.0),
                &put(0.4, 0.4),
                &put(0.0, 1.0),
                &put(1.0, 0.0)
            ));
        }
    }

    #[test]
    fn touching_collinear_and_identical_do_not_count() {
        let (a, b) = ([0.0, 0.0, 0.0], [2.0, 0.0, 0.0]);
        assert!(!segments_cross(&a, &b, &[1.0, 0.0, 0.0], &[1.0, 1.0, 0.0])); // T-junction
        assert!(!segments_cross(&a, &b, &[1.0, 0.0, 0.0], &[3.0, 0.0, 0.0])); // collinear overlap
        assert!(!segments_cross(&a, &b, &a, &b)); // shared edge
        assert!(!segments_cross(&a, &b, &b, &a));
    }
}
