//! [`Quadric`]: the symmetric 4×4 error quadric of Garland & Heckbert's Quadric Error Metric.
//!
//! Thesis ch. 2.3.2: "each vertex was associated with the set of planes in its 1-ring
//! neighbourhood and was expressed by a fundamental quadric matrix; the distance of a point from
//! a set of planes can be expressed using the sum of their quadrics". Garland & Heckbert,
//! "Surface simplification using quadric error metrics", SIGGRAPH 1997.
//!
//! # Conventions
//! A plane `n·x + d = 0` with unit normal `n` and weight `w` gives `Q = w·[n; d][n; d]ᵀ`, stored
//! as its 10 distinct coefficients in `f64`; `Q(v) = [v; 1]ᵀ Q [v; 1] = w·(n·v + d)²` is the
//! weighted squared distance of `v` to the plane. Because `n` is unit, the trace of the 3×3 block
//! equals the total weight, so [`Quadric::weight`] recovers it and
//! `sqrt(Q(v) / Q.weight())` is a weighted RMS distance in the input's units.

use std::ops::{Add, AddAssign};

use meshgnn_geometry::vec3::{cross, dot, sub};

/// A symmetric 4×4 quadric `[[A, b], [bᵀ, c]]` (A 3×3 symmetric), the sum of weighted plane
/// quadrics. Eq. (GH97, §4): `Δ(v) = vᵀ Q v`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Quadric {
    /// `A` upper triangle: a00 a01 a02 a11 a12 a22.
    a: [f64; 6],
    /// `b`: the linear part.
    b: [f64; 3],
    /// `c`: the constant part.
    c: f64,
}

impl Quadric {
    /// The quadric of the plane through `point` with unit `normal`, weighted by `weight`
    /// (QEM uses the face area). `normal` is normalised here; a zero normal gives the zero
    /// quadric.
    ///
    /// ```
    /// use meshgnn_graph::Quadric;
    /// let q = Quadric::from_plane([0.0, 0.0, 1.0], [0.0, 0.0, 2.0], 3.0);
    /// assert!((q.evaluate([5.0, 1.0, 4.0]) - 3.0 * 4.0).abs() < 1e-12);
    /// assert!((q.weight() - 3.0).abs() < 1e-12);
    /// ```
    pub fn from_plane(normal: [f64; 3], point: [f64; 3], weight: f64) -> Self {
        let len = (normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]).sqrt();
        if len.is_nan() || len <= 0.0 || !len.is_finite() {
            return Self::default();
        }
        let n = [normal[0] / len, normal[1] / len, normal[2] / len];
        let d = -(n[0] * point[0] + n[1] * point[1] + n[2] * point[2]);
        let w = weight;
        Self {
            a: [
                w * n[0] * n[0],
                w * n[0] * n[1],
                w * n[0] * n[2],
                w * n[1] * n[1],
                w * n[1] * n[2],
                w * n[2] * n[2],
            ],
            b: [w * n[0] * d, w * n[1] * d, w * n[2] * d],
            c: w * d * d,
        }
    }

    /// The border plane of an open edge `a → b` of a face with normal `face_normal`: through
    /// the edge, perpendicular to the face, weighted by `weight · |b − a|²`. Summed into both
    /// ends' quadrics, it holds a border on its line (GH97 §6: "boundary constraint planes").
    ///
    /// ```
    /// use meshgnn_graph::Quadric;
    /// // The edge (0,0,0) → (2,0,0) of a face in z = 0: the plane y = 0, weight 4.
    /// let q = Quadric::border_plane([0.0; 3], [2.0, 0.0, 0.0], [0.0, 0.0, 1.0], 1.0);
    /// assert!((q.evaluate([5.0, 3.0, 1.0]) - 4.0 * 9.0).abs() < 1e-12);
    /// ```
    #[inline]
    pub fn border_plane(a: [f64; 3], b: [f64; 3], face_normal: [f64; 3], weight: f64) -> Self {
        let e = sub(b, a);
        Self::from_plane(cross(e, face_normal), a, weight * dot(e, e))
    }

    /// `Q(v) = vᵀAv + 2bᵀv + c`: the weighted sum of squared distances of `v` to the planes.
    ///
    /// ```
    /// use meshgnn_graph::Quadric;
    /// let q = Quadric::from_plane([1.0, 0.0, 0.0], [0.0; 3], 1.0)
    ///     + Quadric::from_plane([0.0, 1.0, 0.0], [0.0; 3], 1.0);
    /// assert!((q.evaluate([3.0, 4.0, 7.0]) - 25.0).abs() < 1e-12);
    /// ```
    #[inline]
    pub fn evaluate(&self, v: [f64; 3]) -> f64 {
        let [a00, a01, a02, a11, a12, a22] = self.a;
        let [x, y, z] = v;
        let quad = a00 * x * x
            + a11 * y * y
            + a22 * z * z
            + 2.0 * (a01 * x * y + a02 * x * z + a12 * y * z);
        let lin = 2.0 * (self.b[0] * x + self.b[1] * y + self.b[2] * z);
        // Sums of squares are never negative; round-off can make them slightly so.
        (quad + lin + self.c).max(0.0)
    }

    /// Reads the first and last coefficient (the two cache lines an 80-byte quadric spans),
    /// for the decimation's memory warm-up; the value is meaningless.
    pub(crate) fn touch(&self) -> u32 {
        (self.a[0].to_bits() ^ self.c.to_bits()) as u32
    }

    /// The total weight of the planes summed in (the trace of `A`, since normals are unit).
    pub fn weight(&self) -> f64 {
        self.a[0] + self.a[3] + self.a[5]
    }

    /// The point minimising `Q`: the solution of `A v = −b` (GH97 eq. 1), or `None` when `A` is
    /// ill-conditioned (planes nearly parallel, e.g. a flat or cylindrical region), where the
    /// minimiser is not unique and callers fall back to candidate points.
    ///
    /// The check is scale-free: `|det A|` must exceed `1e-10·(trace A / 3)³`.
    ///
    /// ```
    /// use meshgnn_graph::Quadric;
    /// let corner = [1.0, 2.0, 3.0];
    /// let q = Quadric::from_plane([1.0, 0.0, 0.0], corner, 1.0)
    ///     + Quadric::from_plane([0.0, 1.0, 0.0], corner, 1.0)
    ///     + Quadric::from_plane([0.0, 0.0, 1.0], corner, 1.0);
    /// let v = q.optimal_point().unwrap();
    /// assert!((v[0] - 1.0).abs() < 1e-9 && (v[1] - 2.0).abs() < 1e-9 && (v[2] - 3.0).abs() < 1e-9);
    /// // A single plane has no unique minimiser.
    /// assert!(Quadric::from_plane([0.0, 0.0, 1.0], corner, 1.0).optimal_point().is_none());
    /// ```
    #[inline]
    pub fn optimal_point(&self) -> Option<[f64; 3]> {
        solve_symmetric(self.a, self.b)
    }

    /// The point minimising `Q(v) + μ·|v − anchor|²` with `μ = strength · weight / 3`: the
    /// optimum along the directions the planes pin down, `anchor` along those they leave
    /// free (a flat region moves only along its normal, a crease only across its line), as
    /// Lindstrom's truncated solve does ("Out-of-core simplification of large polygonal
    /// models", SIGGRAPH 2000). `None` for a quadric without planes, non-finite input, or a
    /// `strength` so small (below about 1e-4) that the system fails [`Self::optimal_point`]'s
    /// conditioning test.
    ///
    /// ```
    /// use meshgnn_graph::Quadric;
    /// // A single plane z = 2: the anchor drops onto it and keeps its x and y.
    /// let q = Quadric::from_plane([0.0, 0.0, 1.0], [0.0, 0.0, 2.0], 1.0);
    /// let v = q.regularized_point([5.0, -1.0, 7.0], 1e-3).unwrap();
    /// assert!((v[0] - 5.0).abs() < 1e-9 && (v[1] + 1.0).abs() < 1e-9 && (v[2] - 2.0).abs() < 2e-3);
    /// ```
    pub fn regularized_point(&self, anchor: [f64; 3], strength: f64) -> Option<[f64; 3]> {
        let mu = strength * self.weight() / 3.0;
        let mut a = self.a;
        for diagonal in [0, 3, 5] {
            a[diagonal] += mu;
        }
        solve_symmetric(a, std::array::from_fn(|k| self.b[k] - mu * anchor[k]))
    }
}

/// The solution of `A v = −b` for the symmetric `A` (upper triangle a00 a01 a02 a11 a12 a22),
/// or `None` when `|det A| ≤ 1e-10·(trace A / 3)³` (scale-free) or the result is not finite.
#[inline]
fn solve_symmetric(a: [f64; 6], b: [f64; 3]) -> Option<[f64; 3]> {
    let [a00, a01, a02, a11, a12, a22] = a;
    // Cofactors of the symmetric matrix.
    let c00 = a11 * a22 - a12 * a12;
    let c01 = a02 * a12 - a01 * a22;
    let c02 = a01 * a12 - a02 * a11;
    let det = a00 * c00 + a01 * c01 + a02 * c02;
    let scale = (a00 + a11 + a22) / 3.0;
    let threshold = 1e-10 * scale * scale * scale;
    if scale.is_nan() || scale <= 0.0 || det.is_nan() || det.abs() <= threshold {
        return None;
    }
    let c11 = a00 * a22 - a02 * a02;
    let c12 = a01 * a02 - a00 * a12;
    let c22 = a00 * a11 - a01 * a01;
    let [b0, b1, b2] = b;
    let inv = -1.0 / det;
    let v = [
        inv * (c00 * b0 + c01 * b1 + c02 * b2),
        inv * (c01 * b0 + c11 * b1 + c12 * b2),
        inv * (c02 * b0 + c12 * b1 + c22 * b2),
    ];
    v.iter().all(|x| x.is_finite()).then_some(v)
}

impl Add for Quadric {
    type Output = Self;

    fn add(mut self, rhs: Self) -> Self {
        self += rhs;
        self
    }
}

impl AddAssign for Quadric {
    fn add_assign(&mut self, rhs: Self) {
        for (x, y) in self.a.iter_mut().zip(rhs.a) {
            *x += y;
        }
        for (x, y) in self.b.iter_mut().zip(rhs.b) {
            *x += y;
        }
        self.c += rhs.c;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn evaluates_to_weighted_squared_distance_of_tilted_plane() {
        let n = [1.0, 2.0, 2.0]; // |n| = 3
        let p = [1.0, 0.0, 0.0];
        let q = Quadric::from_plane(n, p, 2.0);
        // Distance of the origin to the plane x + 2y + 2z = 1 is 1/3.
        assert!((q.evaluate([0.0; 3]) - 2.0 / 9.0).abs() < 1e-12);
        assert!(q.evaluate(p).abs() < 1e-12);
    }

    #[test]
    fn optimum_minimises_sum_of_random_planes() {
        let planes = [
            ([0.3, -0.2, 0.9], [0.1, 0.2, 0.3], 1.0),
            ([-0.5, 0.8, 0.1], [0.4, -0.1, 0.0], 2.0),
            ([0.7, 0.6, -0.3], [-0.2, 0.3, 0.5], 0.5),
            ([0.1, 0.1, 1.0], [0.0, 0.0, 1.0], 1.5),
        ];
        let q = planes.iter().fold(Quadric::default(), |acc, &(n, p, w)| {
            acc + Quadric::from_plane(n, p, w)
        });
        let v = q.optimal_point().unwrap();
        let best = q.evaluate(v);
        // The gradient vanishes: any small step increases the cost.
        for axis in 0..3 {
            for step in [-1e-3, 1e-3] {
                let mut w = v;
                w[axis] += step;
                assert!(q.evaluate(w) > best);
            }
        }
    }

    #[test]
    fn two_planes_are_ill_conditioned_and_zero_normal_is_zero_quadric() {
        let q = Quadric::from_plane([1.0, 0.0, 0.0], [0.0; 3], 1.0)
            + Quadric::from_plane([0.0, 1.0, 0.0], [0.0; 3], 1.0);
        assert!(q.optimal_point().is_none());
        assert_eq!(
            Quadric::from_plane([0.0; 3], [1.0; 3], 1.0),
            Quadric::default()
        );
    }
}
