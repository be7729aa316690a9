//! Do two closed triangles share a point? T. Möller, "A fast triangle-triangle intersection
//! test", Journal of Graphics Tools 2(2), 1997: interval overlap on the line where the two
//! planes meet, in `f64`, with a tolerance relative to the coordinates' magnitude.

use meshgnn_geometry::vec3::{cross, dot, norm, sub};

type V3 = [f64; 3];

/// Signed distances of `t`'s corners to the plane of `(n, d)`, with tiny values snapped to 0.
fn plane_distances(n: V3, d: f64, t: &[V3; 3], eps: f64) -> [f64; 3] {
    t.map(|p| {
        let s = dot(n, p) + d;
        if s.abs() < eps { 0.0 } else { s }
    })
}

/// The interval of triangle `t` on the line direction `axis` (Möller's eq. 4-5).
fn interval(t: &[V3; 3], dist: [f64; 3], axis: V3) -> Option<(f64, f64)> {
    let proj = t.map(|p| dot(p, axis));
    // The vertex alone on its side of the plane.
    let lone = if dist[0] * dist[1] > 0.0 {
        2
    } else if dist[0] * dist[2] > 0.0 {
        1
    } else if dist[1] * dist[2] > 0.0 || dist[0] != 0.0 {
        0
    } else if dist[1] != 0.0 {
        1
    } else if dist[2] != 0.0 {
        2
    } else {
        return None; // coplanar
    };
    let (a, b) = ((lone + 1) % 3, (lone + 2) % 3);
    let at = |o: usize| {
        let denom = dist[lone] - dist[o];
        if denom == 0.0 {
            proj[o]
        } else {
            proj[lone] + (proj[o] - proj[lone]) * dist[lone] / denom
        }
    };
    let (x, y) = (at(a), at(b));
    Some((x.min(y), x.max(y)))
}

/// True when the closed triangles `t` and `u` share a point: piercing, touching and coplanar
/// overlap all count (coplanar pairs are tested by edge crossings and containment in 2-D).
/// The validity test of a mesh embedding, where [`super::triangles_intersect`] (penetration
/// only) is the count of the collision loss; callers skip pairs that share a vertex.
///
/// ```
/// use meshgnn_losses::predicates::triangles_meet;
/// let t = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
/// let touching = [[0.2, 0.2, 0.0], [0.2, 0.2, 1.0], [0.3, 0.9, 1.0]]; // a corner on t
/// assert!(triangles_meet(&t, &touching));
/// let above = t.map(|p| [p[0], p[1], 1.0]);
/// assert!(!triangles_meet(&t, &above));
/// ```
pub fn triangles_meet(t: &[V3; 3], u: &[V3; 3]) -> bool {
    let scale = t
        .iter()
        .chain(u)
        .flat_map(|p| p.iter())
        .fold(0.0f64, |m, c| m.max(c.abs()))
        .max(1e-30);
    let eps = 1e-12 * scale;
    let n1 = cross(sub(t[1], t[0]), sub(t[2], t[0]));
    let d1 = -dot(n1, t[0]);
    let du = plane_distances(n1, d1, u, eps * norm(n1));
    if du.iter().all(|&s| s > 0.0) || du.iter().all(|&s| s < 0.0) {
        return false;
    }
    let n2 = cross(sub(u[1], u[0]), sub(u[2], u[0]));
    let d2 = -dot(n2, u[0]);
    let dt = plane_distances(n2, d2, t, eps * norm(n2));
    if dt.iter().all(|&s| s > 0.0) || dt.iter().all(|&s| s < 0.0) {
        return false;
    }
    let axis = cross(n1, n2);
    if dot(axis, axis) <= (eps * eps) * dot(n1, n1) * dot(n2, n2) || du.iter().all(|&s| s == 0.0) {
        return coplanar_intersect(n1, t, u);
    }
    match (interval(t, dt, axis), interval(u, du, axis)) {
        (Some((a0, a1)), Some((b0, b1))) => a0 <= b1 && b0 <= a1,
        _ => coplanar_intersect(n1, t, u),
    }
}

/// Coplanar triangles: project on the dominant plane and test edges and containment.
fn coplanar_intersect(n: V3, t: &[V3; 3], u: &[V3; 3]) -> bool {
    let k = (0..3)
        .max_by(|&i, &j| n[i].abs().total_cmp(&n[j].abs()))
        .unwrap_or(2);
    let (i, j) = ((k + 1) % 3, (k + 2) % 3);
    let p = t.map(|v| [v[i], v[j]]);
    let q = u.map(|v| [v[i], v[j]]);
    let orient = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    // `x` on segment `a`–`b`, given that the three are collinear.
    let on_segment = |a: [f64; 2], b: [f64; 2], x: [f64; 2]| {
        x[0] >= a[0].min(b[0])
            && x[0] <= a[0].max(b[0])
            && x[1] >= a[1].min(b[1])
            && x[1] <= a[1].max(b[1])
    };
    let seg = |a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]| {
        let (o1, o2) = (orient(a, b, c), orient(a, b, d));
        let (o3, o4) = (orient(c, d, a), orient(c, d, b));
        (o1 * o2 < 0.0 && o3 * o4 < 0.0)
            || (o1 == 0.0 && on_segment(a, b, c))
            || (o2 == 0.0 && on_segment(a, b, d))
            || (o3 == 0.0 && on_segment(c, d, a))
            || (o4 == 0.0 && on_segment(c, d, b))
    };
    let inside = |x: [f64; 2], tri: &[[f64; 2]; 3]| {
        let s = [
            orient(tri[0], tri[1], x),
            orient(tri[1], tri[2], x),
            orient(tri[2], tri[0], x),
        ];
        s.iter().all(|&v| v >= 0.0) || s.iter().all(|&v| v <= 0.0)
    };
    (0..3).any(|a| (0..3).any(|b| seg(p[a], p[(a + 1) % 3], q[b], q[(b + 1) % 3])))
        || inside(p[0], &q)
        || inside(q[0], &p)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moller_known_cases() {
        let t = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        // Piercing.
        assert!(triangles_meet(
            &t,
            &[[0.2, 0.2, -1.0], [0.2, 0.2, 1.0], [0.3, 0.9, 1.0]]
        ));
        // Parallel plane above.
        assert!(!triangles_meet(
            &t,
            &[[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]]
        ));
        // Crossing the plane but outside the triangle.
        assert!(!triangles_meet(
            &t,
            &[[2.0, 2.0, -1.0], [2.0, 2.0, 1.0], [3.0, 2.0, 0.0]]
        ));
        // Coplanar with collinear, disjoint edges (a regression: marching-tetrahedra planes).
        let far = [[1.5, 0.0, 0.0], [2.5, 0.0, 0.0], [1.5, 1.0, 0.0]];
        assert!(!triangles_meet(&t, &far));
        // Coplanar overlapping and disjoint.
        assert!(triangles_meet(
            &t,
            &[[0.2, 0.2, 0.0], [2.0, 0.2, 0.0], [0.2, 2.0, 0.0]]
        ));
        assert!(!triangles_meet(
            &t,
            &[[2.0, 2.0, 0.0], [3.0, 2.0, 0.0], [2.0, 3.0, 0.0]]
        ));
    }

    proptest::proptest! {
        #[test]
        fn intersection_is_symmetric_and_separated_triangles_never_meet(
            c in proptest::collection::vec(-1.0f64..1.0, 18),
            gap in 0.01f64..5.0,
        ) {
            let t = [[c[0], c[1], c[2]], [c[3], c[4], c[5]], [c[6], c[7], c[8]]];
            let u = [[c[9], c[10], c[11]], [c[12], c[13], c[14]], [c[15], c[16], c[17]]];
            proptest::prop_assert_eq!(triangles_meet(&t, &u), triangles_meet(&u, &t));
            // Shift u beyond t's x extent: disjoint bounding boxes cannot intersect.
            let shifted = u.map(|p| [p[0] + 2.0 + gap, p[1], p[2]]);
            proptest::prop_assert!(!triangles_meet(&t, &shifted));
        }
    }
}
