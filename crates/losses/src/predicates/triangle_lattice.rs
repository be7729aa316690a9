//! Deterministic interior sample points of a triangle: the centroids of its `n²` sub-triangles
//! after a regular `n`-subdivision. Used where the thesis samples points on each triangle
//! (overlap test of eq. 6.13 with n = 10, i.e. the thesis' 100 points; reverse surface term of
//! eq. 6.10): a fixed lattice needs no seed and covers the triangle uniformly.

/// Barycentric weights `(w_a, w_b, w_c)` of the `n²` sub-triangle centroids; all strictly
/// positive, so every sample lies strictly inside the triangle. Empty for `n = 0`.
///
/// ```
/// use meshgnn_losses::predicates::triangle_lattice;
/// let w = triangle_lattice(2);
/// assert_eq!(w.len(), 4);
/// assert!(w.iter().all(|b| (b[0] + b[1] + b[2] - 1.0).abs() < 1e-6 && b.iter().all(|x| *x > 0.0)));
/// ```
pub fn triangle_lattice(n: usize) -> Vec<[f32; 3]> {
    let nf = n as f64;
    let mut out = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n - i {
            let (u, v) = ((i as f64 + 1.0 / 3.0) / nf, (j as f64 + 1.0 / 3.0) / nf);
            out.push([(1.0 - u - v) as f32, u as f32, v as f32]);
            if i + j + 1 < n {
                let (u, v) = ((i as f64 + 2.0 / 3.0) / nf, (j as f64 + 2.0 / 3.0) / nf);
                out.push([(1.0 - u - v) as f32, u as f32, v as f32]);
            }
        }
    }
    out
}

/// The point with barycentric weights `w` in triangle `t: 3×3`.
pub(crate) fn barycentric_point(t: &[[f32; 3]; 3], w: &[f32; 3]) -> [f32; 3] {
    std::array::from_fn(|k| {
        (f64::from(w[0]) * f64::from(t[0][k])
            + f64::from(w[1]) * f64::from(t[1][k])
            + f64::from(w[2]) * f64::from(t[2][k])) as f32
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lattice_is_uniform() {
        let w = triangle_lattice(10);
        assert_eq!(w.len(), 100);
        // the mean of sub-triangle centroids is the centroid of the triangle
        let mean: Vec<f64> = (0..3)
            .map(|k| w.iter().map(|b| f64::from(b[k])).sum::<f64>() / 100.0)
            .collect();
        for m in mean {
            assert!((m - 1.0 / 3.0).abs() < 1e-6);
        }
        assert!(triangle_lattice(0).is_empty());
    }
}
