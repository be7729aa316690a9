//! Chamfer distance between two point sets (thesis eq. 5.6), in both directions.
//!
//! # Sum or mean
//! Eq. 5.6 writes *sums* of squared nearest-neighbour distances, which grow with the number of
//! points. [`ChamferDistance`] keeps both: the sums (`forward_sum`, `reverse_sum`, the thesis'
//! form, used by the training losses of ch. 5) and the per-point means (`forward_mean`,
//! `reverse_mean`, comparable across sampling densities). The evaluation reports
//! ([`crate::metrics::mesh_evaluation`], [`crate::metrics::point_cloud_evaluation`]) use
//! [`ChamferDistance::symmetric_mean`], in squared unit-sphere units.

use crate::Result;
use crate::deterministic_sum::deterministic_sum;
use crate::morton_order::morton_order;
use crate::point_index::PointIndex;
use crate::validate::check_points;

/// Both directions of the Chamfer distance of eq. 5.6, squared L2, accumulated in `f64`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChamferDistance {
    /// Σ_{x∈A} min_{y∈B} ‖x − y‖²: how well B covers A.
    pub forward_sum: f64,
    /// Σ_{y∈B} min_{x∈A} ‖x − y‖²: how close B stays to A.
    pub reverse_sum: f64,
    /// `forward_sum / |A|`.
    pub forward_mean: f64,
    /// `reverse_sum / |B|`.
    pub reverse_mean: f64,
}

impl ChamferDistance {
    /// Eq. 5.6 exactly: `forward_sum + reverse_sum`.
    pub fn symmetric_sum(&self) -> f64 {
        self.forward_sum + self.reverse_sum
    }

    /// The density-independent form: `forward_mean + reverse_mean`.
    pub fn symmetric_mean(&self) -> f64 {
        self.forward_mean + self.reverse_mean
    }
}

/// Sum of squared distances from each of `queries: #Q×3` to its nearest point in `index`,
/// visiting the queries in Morton order for cache locality.
fn directed_sum(queries: &[[f32; 3]], index: &PointIndex<'_>) -> f64 {
    let order = morton_order(queries);
    deterministic_sum(order.len(), |i| {
        order
            .get(i)
            .and_then(|&j| queries.get(j as usize))
            .map_or(0.0, |q| index.nearest(q).1)
    })
}

/// Eq. 5.6: Chamfer distance between `a: #A×3` and `b: #B×3`, both directions, in O((A + B)
/// log(A + B)) with two k-d trees and parallel queries.
///
/// Fails when either set is empty or holds a non-finite coordinate.
///
/// ```
/// use meshgnn_losses::metrics::chamfer_distance;
/// let a = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]];
/// let b = [[0.0, 0.0, 0.0]];
/// let cd = chamfer_distance(&a, &b)?;
/// assert_eq!(cd.forward_sum, 1.0); // (1,0,0) is 1 away from b
/// assert_eq!(cd.reverse_sum, 0.0);
/// assert_eq!(cd.symmetric_mean(), 0.5);
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn chamfer_distance(a: &[[f32; 3]], b: &[[f32; 3]]) -> Result<ChamferDistance> {
    check_points("first point set", a)?;
    check_points("second point set", b)?;
    let (tree_a, tree_b) = rayon::join(|| PointIndex::new(a), || PointIndex::new(b));
    let (forward_sum, reverse_sum) =
        rayon::join(|| directed_sum(a, &tree_b), || directed_sum(b, &tree_a));
    Ok(ChamferDistance {
        forward_sum,
        reverse_sum,
        forward_mean: forward_sum / a.len() as f64,
        reverse_mean: reverse_sum / b.len() as f64,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshgnn_geometry::vec3::squared_distance_f64;
    use rand::{Rng, SeedableRng, rngs::StdRng};

    fn random_points(n: usize, seed: u64) -> Vec<[f32; 3]> {
        let mut rng = StdRng::seed_from_u64(seed);
        (0..n)
            .map(|_| [rng.random(), rng.random(), rng.random()])
            .collect()
    }

    fn brute_force(a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
        a.iter()
            .map(|x| {
                b.iter()
                    .map(|y| squared_distance_f64(x, y))
                    .fold(f64::INFINITY, f64::min)
            })
            .sum()
    }

    #[test]
    fn identical_sets_give_zero() {
        let a = random_points(500, 1);
        let cd = chamfer_distance(&a, &a).unwrap();
        assert_eq!(cd.symmetric_sum(), 0.0);
    }

    #[test]
    fn hand_computed_three_points() {
        // a = {0, (2,0,0), (0,3,0)}, b = {(1,0,0), (0,3,1)}
        let a = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 3.0, 0.0]];
        let b = [[1.0, 0.0, 0.0], [0.0, 3.0, 1.0]];
        let cd = chamfer_distance(&a, &b).unwrap();
        // forward: 1 + 1 + 1 = 3; reverse: (1,0,0)->0 or (2,0,0): 1; (0,3,1)->(0,3,0): 1
        assert_eq!(cd.forward_sum, 3.0);
        assert_eq!(cd.reverse_sum, 2.0);
        assert_eq!(cd.forward_mean, 1.0);
        assert_eq!(cd.reverse_mean, 1.0);
        assert_eq!(cd.symmetric_sum(), 5.0);
    }

    #[test]
    fn matches_brute_force_on_random_sets() {
        let a = random_points(700, 2);
        let b = random_points(300, 3);
        let cd = chamfer_distance(&a, &b).unwrap();
        let f = brute_force(&a, &b);
        let r = brute_force(&b, &a);
        assert!(
            (cd.forward_sum - f).abs() <= 1e-12 * f.max(1.0),
            "{} {f}",
            cd.forward_sum
        );
        assert!(
            (cd.reverse_sum - r).abs() <= 1e-12 * r.max(1.0),
            "{} {r}",
            cd.reverse_sum
        );
    }

    #[test]
    fn duplicates_are_fine() {
        let a = vec![[0.5f32; 3]; 200];
        let b = [[0.5, 0.5, 1.5]];
        let cd = chamfer_distance(&a, &b).unwrap();
        assert!((cd.forward_sum - 200.0).abs() < 1e-9);
        assert!((cd.reverse_sum - 1.0).abs() < 1e-12);
    }

    #[test]
    fn rejects_empty_and_nan() {
        assert!(chamfer_distance(&[], &[[0.0; 3]]).is_err());
        assert!(chamfer_distance(&[[f32::NAN, 0.0, 0.0]], &[[0.0; 3]]).is_err());
    }

    proptest::proptest! {
        #[test]
        fn invariant_to_point_order(seed in 0u64..1000, shift in 0usize..50) {
            let a = random_points(60, seed);
            let b = random_points(40, seed + 1);
            let mut a2 = a.clone();
            a2.rotate_left(shift);
            a2.reverse();
            let cd1 = chamfer_distance(&a, &b).unwrap();
            let cd2 = chamfer_distance(&a2, &b).unwrap();
            proptest::prop_assert!((cd1.symmetric_sum() - cd2.symmetric_sum()).abs() < 1e-12);
        }
    }
}
