//! Small `f64` vector helpers, shared by the operators of every meshgnn crate so quadrics,
//! predicates and normals use one definition, and the one finiteness scan behind every crate's
//! input check.

/// Index of the first element of `values: #N×K` with a NaN or infinite component, if any: the
/// scan behind each crate's `check_finite`, which wraps the index in its own error.
///
/// ```
/// use meshgnn_geometry::vec3::first_non_finite;
/// assert_eq!(first_non_finite(&[[0.0f32, 1.0, 2.0], [3.0, f32::NAN, 0.0]]), Some(1));
/// assert_eq!(first_non_finite(&[[0.0f32, 1.0], [f32::INFINITY, 0.0]]), Some(1));
/// assert_eq!(first_non_finite::<3>(&[[1.0, 2.0, 3.0]]), None);
/// ```
#[inline]
pub fn first_non_finite<const K: usize>(values: &[[f32; K]]) -> Option<usize> {
    values.iter().position(|v| v.iter().any(|x| !x.is_finite()))
}

/// `p` widened to `f64`.
#[inline]
pub fn to_f64(p: [f32; 3]) -> [f64; 3] {
    [f64::from(p[0]), f64::from(p[1]), f64::from(p[2])]
}

/// `|a − b|²` of two `f32` points, accumulated in `f64` (exact for the metrics; the spatial
/// index's own [`crate::squared_distance`] stays in `f32`, its one evaluation order).
#[inline]
pub fn squared_distance_f64(a: &[f32; 3], b: &[f32; 3]) -> f64 {
    let d = sub(to_f64(*a), to_f64(*b));
    dot(d, d)
}

/// `a − b`.
#[inline]
pub fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `a × b`.
#[inline]
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `a · b`.
#[inline]
pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `|a|`.
#[inline]
pub fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// `a / |a|` as `f32`, or zero when `|a| = 0`.
#[inline]
pub fn unit_f32(a: [f64; 3]) -> [f32; 3] {
    let n = norm(a);
    if n > 0.0 && n.is_finite() {
        [(a[0] / n) as f32, (a[1] / n) as f32, (a[2] / n) as f32]
    } else {
        [0.0; 3]
    }
}

/// The doubled-area vector `(b − a) × (c − a)` of a triangle, in `f64`.
#[inline]
pub fn triangle_cross(corners: [[f32; 3]; 3]) -> [f64; 3] {
    let [a, b, c] = corners.map(to_f64);
    cross(sub(b, a), sub(c, a))
}
