//! Unit-sphere normalisation: translate the centroid to the origin and scale the farthest
//! point to distance 1. The project's metrics normalise both shapes by the *original's*
//! centroid and bounding-sphere radius, so figures are comparable across meshes (SPEC §3).

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::tri_mesh::check_finite;
use crate::vec3::{dot, sub, to_f64};

/// A similarity `p ↦ (p − center) / radius` (computed in `f64`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Normalization {
    /// The centroid of the reference points.
    pub center: [f64; 3],
    /// The largest distance of a reference point from `center` (1 when all coincide).
    pub radius: f64,
}

impl Normalization {
    /// `(p − center) / radius` for every point of `points: #P×3`.
    ///
    /// ```
    /// use meshgnn_geometry::Normalization;
    /// let n = Normalization { center: [1.0, 0.0, 0.0], radius: 2.0 };
    /// assert_eq!(n.apply(&[[3.0, 2.0, 0.0]]), vec![[1.0, 1.0, 0.0]]);
    /// ```
    pub fn apply(&self, points: &[[f32; 3]]) -> Vec<[f32; 3]> {
        let (c, r) = (self.center, self.radius);
        points
            .par_iter()
            .map(|p| {
                let d = sub(to_f64(*p), c);
                [(d[0] / r) as f32, (d[1] / r) as f32, (d[2] / r) as f32]
            })
            .collect()
    }

    /// The inverse map `q ↦ q · radius + center`, back to the original frame.
    ///
    /// ```
    /// use meshgnn_geometry::Normalization;
    /// let n = Normalization { center: [1.0, 0.0, 0.0], radius: 2.0 };
    /// assert_eq!(n.invert(&[[1.0, 1.0, 0.0]]), vec![[3.0, 2.0, 0.0]]);
    /// ```
    pub fn invert(&self, points: &[[f32; 3]]) -> Vec<[f32; 3]> {
        let (c, r) = (self.center, self.radius);
        points
            .par_iter()
            .map(|p| {
                let q = to_f64(*p);
                [0, 1, 2].map(|i| (q[i] * r + c[i]) as f32)
            })
            .collect()
    }
}

/// The normalisation of `points: #P×3`: centre = centroid, radius = max distance from it
/// (1 if every point coincides, so `apply` only translates). Fails on an empty or non-finite
/// input.
///
/// ```
/// use meshgnn_geometry::unit_sphere_normalization;
/// let n = unit_sphere_normalization(&[[0.0, 0.0, 0.0], [4.0, 0.0, 0.0]])?;
/// assert_eq!((n.center, n.radius), ([2.0, 0.0, 0.0], 2.0));
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn unit_sphere_normalization(points: &[[f32; 3]]) -> Result<Normalization> {
    if points.is_empty() {
        return Err(Error::Empty { what: "points" });
    }
    check_finite("point", points)?;
    let center = centroid(points);
    let max_sq = points
        .par_iter()
        .map(|p| {
            let d = sub(to_f64(*p), center);
            dot(d, d)
        })
        .reduce(|| 0.0, f64::max);
    let radius = if max_sq > 0.0 { max_sq.sqrt() } else { 1.0 };
    Ok(Normalization { center, radius })
}

/// Mean of `points: #P×3` in `f64`, summed in fixed-size chunks so that the result does not
/// depend on the number of threads (0 for an empty input).
pub(crate) fn centroid(points: &[[f32; 3]]) -> [f64; 3] {
    let partial: Vec<[f64; 3]> = points
        .par_chunks(4096)
        .map(|chunk| {
            chunk.iter().fold([0.0; 3], |s, p| {
                let p = to_f64(*p);
                [s[0] + p[0], s[1] + p[1], s[2] + p[2]]
            })
        })
        .collect();
    let sum = partial
        .iter()
        .fold([0.0; 3], |s, p| [s[0] + p[0], s[1] + p[1], s[2] + p[2]]);
    let n = points.len().max(1) as f64;
    sum.map(|x| x / n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::subdivided_cube;

    #[test]
    fn normalized_cloud_has_zero_centroid_and_unit_radius_and_inverts() {
        let points: Vec<[f32; 3]> = subdivided_cube(3)
            .vertices()
            .iter()
            .map(|p| [p[0] * 3.0 + 10.0, p[1] * 0.5 - 2.0, p[2] + 7.0])
            .collect();
        let n = unit_sphere_normalization(&points).unwrap();
        let unit = n.apply(&points);
        let c = centroid(&unit);
        assert!(c.iter().all(|x| x.abs() < 1e-6), "{c:?}");
        let r = unit
            .iter()
            .map(|p| dot(to_f64(*p), to_f64(*p)).sqrt())
            .fold(0.0, f64::max);
        assert!((r - 1.0).abs() < 1e-6);
        for (a, b) in n.invert(&unit).iter().zip(&points) {
            assert!((0..3).all(|i| (a[i] - b[i]).abs() < 1e-5));
        }
        assert!(unit_sphere_normalization(&[]).is_err());
        assert_eq!(
            unit_sphere_normalization(&[[1.0; 3]; 3]).unwrap().radius,
            1.0
        );
    }
}
