//! Normal consistency NC between two oriented point clouds (thesis eq. 5.14).

use crate::Result;
use crate::deterministic_sum::deterministic_sum;
use crate::point_index::PointIndex;
use crate::validate::{check_finite, check_len, check_points};

/// Whether the sign of a normal carries information.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum NormalOrientation {
    /// Normals point outwards consistently (mesh normals): `1 − cos θ`, in [0, 2].
    #[default]
    Oriented,
    /// Normals have an arbitrary sign (PCA normals of eq. 5.1): `1 − |cos θ|`, in [0, 1].
    Unoriented,
}

/// `1 − cos` (or `1 − |cos|`) of the angle between two normals, in `f64`. A zero-length
/// normal carries no direction and scores the neutral cosine 0 (penalty 1).
pub(crate) fn normal_dissimilarity(
    a: &[f32; 3],
    b: &[f32; 3],
    orientation: NormalOrientation,
) -> f64 {
    let a = a.map(f64::from);
    let b = b.map(f64::from);
    let dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let na = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    let nb = (b[0] * b[0] + b[1] * b[1] + b[2] * b[2]).sqrt();
    let cos = if na > 0.0 && nb > 0.0 {
        (dot / (na * nb)).clamp(-1.0, 1.0)
    } else {
        0.0
    };
    match orientation {
        NormalOrientation::Oriented => 1.0 - cos,
        NormalOrientation::Unoriented => 1.0 - cos.abs(),
    }
}

/// Mean of `1 − cos(n_x, n_{NN(x, B)})` over `x ∈ A`: one direction of eq. 5.14.
pub(crate) fn directed_normal_error(
    points: &[[f32; 3]],
    normals: &[[f32; 3]],
    target: &PointIndex<'_>,
    target_normals: &[[f32; 3]],
    orientation: NormalOrientation,
) -> f64 {
    let sum = deterministic_sum(points.len(), |i| {
        let (Some(p), Some(n)) = (points.get(i), normals.get(i)) else {
            return 0.0;
        };
        let (j, _) = target.nearest(p);
        target_normals
            .get(j)
            .map_or(0.0, |m| normal_dissimilarity(n, m, orientation))
    });
    sum / points.len() as f64
}

/// Eq. 5.14: `NC = mean_{x∈A} (1 − cos(n_x, n_{NN(x,B)})) + mean_{y∈B} (1 − cos(n_y,
/// n_{NN(y,A)}))` for `points_a, normals_a: #A×3` and `points_b, normals_b: #B×3`.
/// Dimensionless, in [0, 4] (oriented) or [0, 2] (unoriented); 0 for identical clouds.
///
/// ```
/// use meshgnn_losses::metrics::{normal_consistency, NormalOrientation};
/// let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]];
/// let up = [[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]];
/// let tilted = [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]; // second normal 90° off
/// let nc = normal_consistency(&p, &up, &p, &tilted, NormalOrientation::Oriented)?;
/// assert!((nc - 1.0).abs() < 1e-12); // 0.5 each way
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn normal_consistency(
    points_a: &[[f32; 3]],
    normals_a: &[[f32; 3]],
    points_b: &[[f32; 3]],
    normals_b: &[[f32; 3]],
    orientation: NormalOrientation,
) -> Result<f64> {
    check_points("first point set", points_a)?;
    check_points("second point set", points_b)?;
    check_len("normals of the first set", points_a.len(), normals_a.len())?;
    check_len("normals of the second set", points_b.len(), normals_b.len())?;
    check_finite("normals of the first set", normals_a)?;
    check_finite("normals of the second set", normals_b)?;
    let (tree_a, tree_b) = rayon::join(|| PointIndex::new(points_a), || PointIndex::new(points_b));
    let (f, r) = rayon::join(
        || directed_normal_error(points_a, normals_a, &tree_b, normals_b, orientation),
        || directed_normal_error(points_b, normals_b, &tree_a, normals_a, orientation),
    );
    Ok(f + r)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_is_zero() {
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let n = [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]];
        let nc = normal_consistency(&p, &n, &p, &n, NormalOrientation::Oriented).unwrap();
        assert!(nc < 1e-15);
    }

    #[test]
    fn flipped_normals_oriented_vs_unoriented() {
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]];
        let n = [[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]];
        let flipped = [[0.0, 0.0, -1.0], [0.0, 0.0, -1.0]];
        let o = normal_consistency(&p, &n, &p, &flipped, NormalOrientation::Oriented).unwrap();
        let u = normal_consistency(&p, &n, &p, &flipped, NormalOrientation::Unoriented).unwrap();
        assert!((o - 4.0).abs() < 1e-12);
        assert_eq!(u, 0.0);
    }

    #[test]
    fn hand_computed_asymmetric() {
        // A has 2 points, B has 1 point at A[0] with a normal 60° from A[0]'s and 90° from A[1]'s.
        let pa = [[0.0, 0.0, 0.0], [5.0, 0.0, 0.0]];
        let na = [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]];
        let s = 3f32.sqrt() / 2.0;
        let pb = [[0.0, 0.0, 0.0]];
        let nb = [[0.0, s, 0.5]];
        let nc = normal_consistency(&pa, &na, &pb, &nb, NormalOrientation::Oriented).unwrap();
        // forward: (0.5 + 1.0) / 2 = 0.75; reverse: 0.5
        assert!((nc - 1.25).abs() < 1e-6, "{nc}");
        // order of A does not matter
        let pa2 = [pa[1], pa[0]];
        let na2 = [na[1], na[0]];
        let nc2 = normal_consistency(&pa2, &na2, &pb, &nb, NormalOrientation::Oriented).unwrap();
        assert!((nc - nc2).abs() < 1e-12);
    }

    #[test]
    fn rejects_length_mismatch() {
        let p = [[0.0f32; 3]];
        assert!(normal_consistency(&p, &[], &p, &p, NormalOrientation::Oriented).is_err());
    }
}
