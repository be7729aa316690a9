//! Small `f64` vector and rotation helpers shared by the generators (private to the crate);
//! the basic products come from `meshgnn_geometry::vec3`.

pub(crate) use meshgnn_geometry::vec3::{cross, dot, norm, sub};

/// A 3-vector.
pub(crate) type V3 = [f64; 3];
/// A 3×3 matrix, row major.
pub(crate) type M3 = [[f64; 3]; 3];

/// `a + b`.
#[inline]
pub(crate) fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// `s·a`.
#[inline]
pub(crate) fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// `a / |a|`, or `a` unchanged when `|a| = 0`.
#[inline]
pub(crate) fn normalize(a: V3) -> V3 {
    let n = norm(a);
    if n > 0.0 { scale(a, 1.0 / n) } else { a }
}

/// `m · v`.
#[inline]
pub(crate) fn mul_v(m: &M3, v: V3) -> V3 {
    [dot(m[0], v), dot(m[1], v), dot(m[2], v)]
}

/// `a · b`.
pub(crate) fn mul_m(a: &M3, b: &M3) -> M3 {
    let mut out = [[0.0; 3]; 3];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, value) in row.iter_mut().enumerate() {
            *value = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    out
}

/// Column `j` of `m` (the image of the `j`-th basis vector).
#[inline]
pub(crate) fn column(m: &M3, j: usize) -> V3 {
    [m[0][j], m[1][j], m[2][j]]
}

/// Rotation by `angle` radians about the unit `axis` (Rodrigues' formula).
pub(crate) fn axis_angle(axis: V3, angle: f64) -> M3 {
    let [x, y, z] = normalize(axis);
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
    ]
}

/// The transpose of `m` (the inverse of a rotation).
pub(crate) fn transpose(m: &M3) -> M3 {
    std::array::from_fn(|i| std::array::from_fn(|j| m[j][i]))
}

/// The rotation by `t` times the angle of the rotation `r`, about the same axis (for
/// rotations of less than a half turn).
pub(crate) fn rotation_fraction(r: &M3, t: f64) -> M3 {
    let angle = ((r[0][0] + r[1][1] + r[2][2] - 1.0) / 2.0)
        .clamp(-1.0, 1.0)
        .acos();
    let axis = [r[2][1] - r[1][2], r[0][2] - r[2][0], r[1][0] - r[0][1]];
    if norm(axis) < 1e-12 {
        return axis_angle([1.0, 0.0, 0.0], 0.0);
    }
    axis_angle(axis, t * angle)
}

/// `p` widened to `f64`.
#[inline]
pub(crate) fn to_f64(p: [f32; 3]) -> V3 {
    [f64::from(p[0]), f64::from(p[1]), f64::from(p[2])]
}

/// `p` narrowed to `f32`.
#[inline]
pub(crate) fn to_f32(p: V3) -> [f32; 3] {
    [p[0] as f32, p[1] as f32, p[2] as f32]
}

/// A per-item seed derived from a dataset seed and an index (SplitMix64 finaliser), so that
/// item `i` is the same whatever the thread count or the number of items generated.
pub(crate) fn item_seed(seed: u64, index: u64) -> u64 {
    let mut z = seed ^ index.wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}
