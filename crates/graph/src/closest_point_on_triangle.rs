//! Barycentric coordinates of the point of a triangle closest to a query point, by the Voronoi
//! regions of the triangle's vertices, edges and interior (the classical region test, e.g.
//! Ericson, "Real-Time Collision Detection", 2005, §5.1.5), in `f64`.

/// Barycentric weights `(wa, wb, wc)` (non-negative, summing to 1) of the point of triangle
/// `(a, b, c)` closest to `p`, and its squared distance to `p`. A degenerate triangle falls back
/// to its closest corner.
pub(crate) fn closest_point_on_triangle(
    p: [f64; 3],
    a: [f64; 3],
    b: [f64; 3],
    c: [f64; 3],
) -> ([f64; 3], f64) {
    let sub = |x: [f64; 3], y: [f64; 3]| [x[0] - y[0], x[1] - y[1], x[2] - y[2]];
    let dot = |x: [f64; 3], y: [f64; 3]| x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(p, a));
    let (d1, d2) = (dot(ab, ap), dot(ac, ap));
    let weights = 'region: {
        if d1 <= 0.0 && d2 <= 0.0 {
            break 'region [1.0, 0.0, 0.0];
        }
        let bp = sub(p, b);
        let (d3, d4) = (dot(ab, bp), dot(ac, bp));
        if d3 >= 0.0 && d4 <= d3 {
            break 'region [0.0, 1.0, 0.0];
        }
        let vc = d1 * d4 - d3 * d2;
        if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 && d1 - d3 > 0.0 {
            let v = d1 / (d1 - d3);
            break 'region [1.0 - v, v, 0.0];
        }
        let cp = sub(p, c);
        let (d5, d6) = (dot(ab, cp), dot(ac, cp));
        if d6 >= 0.0 && d5 <= d6 {
            break 'region [0.0, 0.0, 1.0];
        }
        let vb = d5 * d2 - d1 * d6;
        if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 && d2 - d6 > 0.0 {
            let w = d2 / (d2 - d6);
            break 'region [1.0 - w, 0.0, w];
        }
        let va = d3 * d6 - d5 * d4;
        let (e1, e2) = (d4 - d3, d5 - d6);
        if va <= 0.0 && e1 >= 0.0 && e2 >= 0.0 && e1 + e2 > 0.0 {
            let w = e1 / (e1 + e2);
            break 'region [0.0, 1.0 - w, w];
        }
        let sum = va + vb + vc;
        if sum > 0.0 && sum.is_finite() {
            let (v, w) = (vb / sum, vc / sum);
            break 'region [1.0 - v - w, v, w];
        }
        // Degenerate triangle: the nearest corner.
        let corners = [a, b, c].map(|q| dot(sub(p, q), sub(p, q)));
        let best = (0..3).fold(0, |m, i| if corners[i] < corners[m] { i } else { m });
        let mut w = [0.0; 3];
        w[best] = 1.0;
        w
    };
    let q: [f64; 3] =
        std::array::from_fn(|i| weights[0] * a[i] + weights[1] * b[i] + weights[2] * c[i]);
    let d = sub(p, q);
    (weights, dot(d, d))
}

#[cfg(test)]
mod tests {
    use super::*;

    const A: [f64; 3] = [0.0, 0.0, 0.0];
    const B: [f64; 3] = [2.0, 0.0, 0.0];
    const C: [f64; 3] = [0.0, 2.0, 0.0];

    #[test]
    fn every_voronoi_region_gives_the_hand_computed_answer() {
        let cases: [([f64; 3], [f64; 3], f64); 7] = [
            ([0.5, 0.5, 1.0], [0.5, 0.25, 0.25], 1.0), // interior, above
            ([-1.0, -1.0, 0.0], [1.0, 0.0, 0.0], 2.0), // corner a
            ([3.0, -1.0, 0.0], [0.0, 1.0, 0.0], 2.0),  // corner b
            ([-1.0, 3.0, 0.0], [0.0, 0.0, 1.0], 2.0),  // corner c
            ([1.0, -1.0, 0.0], [0.5, 0.5, 0.0], 1.0),  // edge ab
            ([-1.0, 1.0, 0.0], [0.5, 0.0, 0.5], 1.0),  // edge ac
            ([2.0, 2.0, 0.0], [0.0, 0.5, 0.5], 2.0),   // edge bc
        ];
        for (p, weights, dist2) in cases {
            let (w, d) = closest_point_on_triangle(p, A, B, C);
            for i in 0..3 {
                assert!((w[i] - weights[i]).abs() < 1e-12, "{p:?}: {w:?}");
            }
            assert!((d - dist2).abs() < 1e-12, "{p:?}: {d}");
        }
    }

    #[test]
    fn degenerate_triangle_falls_back_to_nearest_corner() {
        let (w, d) = closest_point_on_triangle([5.0, 1.0, 0.0], A, A, A);
        assert_eq!(w.iter().sum::<f64>(), 1.0);
        assert!((d - 26.0).abs() < 1e-12);
    }
}
