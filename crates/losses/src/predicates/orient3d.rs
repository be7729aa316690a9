//! The 3-d orientation predicate with a forward error bound (Shewchuk 1997, "Adaptive
//! precision floating-point arithmetic and fast robust geometric predicates", DCG 18).
//!
//! Inputs are `f32`, evaluated in `f64`: the coordinate differences are exact, and the
//! determinant carries a rounding error below [`orient3d`]'s bound. A value inside the bound
//! is reported as `0` (coplanar), so every caller sees a consistent sign: the three-way answer
//! is never a rounding artefact. Points within the bound of a plane count as on it.

use meshgnn_geometry::vec3::sub;

/// Relative error bound of the `f64` determinant (Shewchuk's `o3derrboundA`).
const ERRBOUND: f64 = (7.0 + 56.0 * f64::EPSILON) * f64::EPSILON;

/// Converts an `f32` point to `f64`.
pub(crate) fn widen(p: &[f32; 3]) -> [f64; 3] {
    p.map(f64::from)
}

/// Sign of the volume of the tetrahedron `(a, b, c, d)`: `+1` when `d` lies below the plane of
/// the counter-clockwise triangle `(a, b, c)` (opposite its normal), `−1` above, `0` on it
/// (within the rounding bound).
pub(crate) fn orient3d(a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3]) -> i8 {
    let (ad, bd, cd) = (sub(a, d), sub(b, d), sub(c, d));
    let det = ad[0] * (bd[1] * cd[2] - bd[2] * cd[1])
        + bd[0] * (cd[1] * ad[2] - cd[2] * ad[1])
        + cd[0] * (ad[1] * bd[2] - ad[2] * bd[1]);
    let permanent = ad[0].abs() * ((bd[1] * cd[2]).abs() + (bd[2] * cd[1]).abs())
        + bd[0].abs() * ((cd[1] * ad[2]).abs() + (cd[2] * ad[1]).abs())
        + cd[0].abs() * ((ad[1] * bd[2]).abs() + (ad[2] * bd[1]).abs());
    let bound = ERRBOUND * permanent;
    if det > bound {
        1
    } else if det < -bound {
        -1
    } else {
        0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn signs() {
        let (a, b, c) = ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        assert_eq!(orient3d(a, b, c, [0.2, 0.2, -1.0]), 1);
        assert_eq!(orient3d(a, b, c, [0.2, 0.2, 1.0]), -1);
        assert_eq!(orient3d(a, b, c, [5.0, -3.0, 0.0]), 0);
        // a point on a large tilted plane, built from f32 coordinates, stays coplanar
        let (p, q, r) = ([1e3, 0.0, 0.0], [0.0, 1e3, 0.0], [0.0, 0.0, 1e3]);
        assert_eq!(orient3d(p, q, r, [250.0, 250.0, 500.0]), 0);
    }
}
