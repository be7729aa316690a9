//! Starting orientations for fitting a model to a scan in an unknown pose (beyond the thesis,
//! whose scans are pre-aligned): the identity, and the four proper rotations that map the
//! model's principal axes onto the scan's (each axis matched up to its sign, the third sign
//! fixed by det R = +1). [`crate::fit_scan`] tries each, on the scan and on its mirror image.

use meshgnn_geometry::symmetric_eigen3;

/// Unit quaternions `(w, x, y, z)`: the identity first, then the principal-axis alignments of
/// `model` (its mean shape) onto `scan`.
pub(crate) fn starting_rotations(model: &[[f32; 3]], scan: &[[f32; 3]]) -> Vec<[f64; 4]> {
    let (m, s) = (principal_axes(model), principal_axes(scan));
    let mut starts = vec![[1.0, 0.0, 0.0, 0.0]];
    for (a, b) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
        let c = a * b * determinant(s) * determinant(m);
        let signs = [a, b, c];
        // R = Σ_k sign_k · s_k m_kᵀ maps model axis k onto ± scan axis k.
        let r: [[f64; 3]; 3] = std::array::from_fn(|i| {
            std::array::from_fn(|j| (0..3).map(|k| signs[k] * s[k][i] * m[k][j]).sum())
        });
        starts.push(quaternion_from_matrix(r));
    }
    starts
}

/// The eigenvectors of the points' covariance, largest variance first (rows).
fn principal_axes(points: &[[f32; 3]]) -> [[f64; 3]; 3] {
    let n = points.len().max(1) as f64;
    let mean: [f64; 3] =
        std::array::from_fn(|k| points.iter().map(|p| f64::from(p[k])).sum::<f64>() / n);
    let covariance: [[f64; 3]; 3] = std::array::from_fn(|i| {
        std::array::from_fn(|j| {
            points
                .iter()
                .map(|p| (f64::from(p[i]) - mean[i]) * (f64::from(p[j]) - mean[j]))
                .sum::<f64>()
                / n
        })
    });
    let (_, vectors) = symmetric_eigen3(covariance);
    [vectors[2], vectors[1], vectors[0]]
}

fn determinant(rows: [[f64; 3]; 3]) -> f64 {
    let [a, b, c] = rows;
    a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
        + a[2] * (b[0] * c[1] - b[1] * c[0])
}

/// The unit quaternion of a rotation matrix (row-major), by the largest of its four
/// candidate components (Shepperd, 1978), so it is stable for every angle.
fn quaternion_from_matrix(r: [[f64; 3]; 3]) -> [f64; 4] {
    let trace = r[0][0] + r[1][1] + r[2][2];
    let q = if trace > r[0][0].max(r[1][1]).max(r[2][2]) {
        let w = 0.5 * (1.0 + trace).sqrt();
        [
            w,
            (r[2][1] - r[1][2]) / (4.0 * w),
            (r[0][2] - r[2][0]) / (4.0 * w),
            (r[1][0] - r[0][1]) / (4.0 * w),
        ]
    } else if r[0][0] >= r[1][1] && r[0][0] >= r[2][2] {
        let x = 0.5 * (1.0 + r[0][0] - r[1][1] - r[2][2]).sqrt();
        [
            (r[2][1] - r[1][2]) / (4.0 * x),
            x,
            (r[0][1] + r[1][0]) / (4.0 * x),
            (r[0][2] + r[2][0]) / (4.0 * x),
        ]
    } else if r[1][1] >= r[2][2] {
        let y = 0.5 * (1.0 + r[1][1] - r[0][0] - r[2][2]).sqrt();
        [
            (r[0][2] - r[2][0]) / (4.0 * y),
            (r[0][1] + r[1][0]) / (4.0 * y),
            y,
            (r[1][2] + r[2][1]) / (4.0 * y),
        ]
    } else {
        let z = 0.5 * (1.0 + r[2][2] - r[0][0] - r[1][1]).sqrt();
        [
            (r[1][0] - r[0][1]) / (4.0 * z),
            (r[0][2] + r[2][0]) / (4.0 * z),
            (r[1][2] + r[2][1]) / (4.0 * z),
            z,
        ]
    };
    let norm = q.iter().map(|c| c * c).sum::<f64>().sqrt();
    q.map(|c| c / norm)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SimilarityTransform;
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    #[test]
    fn quaternion_round_trips_through_the_matrix_at_any_angle() {
        for (axis, degrees) in [
            ([1.0, 2.0, 3.0], 10.0),
            ([0.0, 1.0, 0.0], 179.0),
            ([1.0, -1.0, 0.5], 120.0),
            ([0.0, 0.0, 1.0], 0.0),
        ] {
            let t =
                SimilarityTransform::from_axis_angle(1.0, axis, f64::to_radians(degrees), [0.0; 3]);
            let q = quaternion_from_matrix(t.rotation_matrix());
            let dot: f64 = (0..4).map(|k| q[k] * t.rotation[k]).sum();
            assert!((dot.abs() - 1.0).abs() < 1e-12, "{q:?} vs {:?}", t.rotation);
        }
    }

    #[test]
    fn one_start_undoes_a_rotation_of_an_elongated_shape() {
        // A box-like cloud with three distinct extents, rotated by 150° about (1, 2, 3).
        let mut rng = StdRng::seed_from_u64(5);
        let model: Vec<[f32; 3]> = (0..1000)
            .map(|_| [4.0, 2.0, 1.0].map(|e: f32| e * rng.random_range(-0.5..0.5)))
            .collect();
        let truth = SimilarityTransform::from_axis_angle(
            1.0,
            [1.0, 2.0, 3.0],
            150f64.to_radians(),
            [0.0; 3],
        );
        let scan: Vec<[f32; 3]> = model.iter().map(|&p| truth.apply(p)).collect();
        let starts = starting_rotations(&model, &scan);
        assert_eq!(starts.len(), 5);
        let best = starts
            .iter()
            .map(|q| {
                let dot: f64 = (0..4).map(|k| q[k] * truth.rotation[k]).sum();
                dot.abs()
            })
            .fold(0.0, f64::max);
        assert!(best > 0.999, "closest start {best}");
    }
}
