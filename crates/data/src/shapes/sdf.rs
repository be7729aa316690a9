//! Signed distance primitives and blends for the procedural shapes (I. Quilez's classic
//! formulas; smooth minimum from Quilez, "smooth minimum", 2013). Private to the crate.

use crate::vec3::{V3, dot, norm, sub};

/// Sphere of radius `r` at `c`.
pub(crate) fn sphere(p: V3, c: V3, r: f64) -> f64 {
    norm(sub(p, c)) - r
}

/// Axis-aligned box of half-extents `b` centred at `c`, edges rounded by `r`.
pub(crate) fn round_box(p: V3, c: V3, b: V3, r: f64) -> f64 {
    let q = [0, 1, 2].map(|k| (p[k] - c[k]).abs() - (b[k] - r));
    let outside = norm(q.map(|x| x.max(0.0)));
    outside + q[0].max(q[1]).max(q[2]).min(0.0) - r
}

/// Capsule (segment `a`–`b`, radius `r`).
pub(crate) fn capsule(p: V3, a: V3, b: V3, r: f64) -> f64 {
    let (pa, ba) = (sub(p, a), sub(b, a));
    let h = (dot(pa, ba) / dot(ba, ba).max(1e-30)).clamp(0.0, 1.0);
    norm(sub(pa, ba.map(|x| x * h))) - r
}

/// Cylinder along z centred at `c`, radius `r`, half-height `h`.
pub(crate) fn cylinder_z(p: V3, c: V3, r: f64, h: f64) -> f64 {
    let d = [
        ((p[0] - c[0]).hypot(p[1] - c[1])) - r,
        (p[2] - c[2]).abs() - h,
    ];
    d[0].max(d[1]).min(0.0) + d[0].max(0.0).hypot(d[1].max(0.0))
}

/// Ellipsoid with radii `r` at `c` (the usual bound-preserving approximation).
pub(crate) fn ellipsoid(p: V3, c: V3, r: V3) -> f64 {
    let q = [0, 1, 2].map(|k| (p[k] - c[k]) / r[k]);
    let k0 = norm(q);
    let k1 = norm([0, 1, 2].map(|k| q[k] / r[k]));
    if k1 > 0.0 {
        k0 * (k0 - 1.0) / k1
    } else {
        -r[0].min(r[1]).min(r[2])
    }
}

/// Polynomial smooth minimum with blend radius `k`.
pub(crate) fn smin(a: f64, b: f64, k: f64) -> f64 {
    let h = (0.5 + 0.5 * (b - a) / k).clamp(0.0, 1.0);
    b + (a - b) * h - k * h * (1.0 - h)
}

/// Smooth maximum (blended intersection / subtraction).
pub(crate) fn smax(a: f64, b: f64, k: f64) -> f64 {
    -smin(-a, -b, k)
}
