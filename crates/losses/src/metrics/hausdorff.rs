//! Symmetric Hausdorff distance between two point sets (the worst-case surface deviation of
//! thesis ch. 5.3.3, reported by `meshsimplify eval`).

use crate::Result;
use crate::morton_order::morton_order;
use crate::point_index::PointIndex;
use crate::validate::check_points;
use rayon::prelude::*;

/// max_{x∈A} min_{y∈B} ‖x − y‖: the farthest any point of `queries` is from `index`.
fn directed_hausdorff(queries: &[[f32; 3]], index: &PointIndex<'_>) -> f64 {
    morton_order(queries)
        .par_iter()
        .with_min_len(1024)
        .filter_map(|&j| queries.get(j as usize))
        .map(|q| index.nearest(q).1)
        .reduce(|| 0.0, f64::max)
        .sqrt()
}

/// Hausdorff distance `max(h(A, B), h(B, A))` between `a: #A×3` and `b: #B×3`, with
/// `h(A, B) = max_{x∈A} min_{y∈B} ‖x − y‖` (Euclidean, not squared; same units as the input).
///
/// Fails when either set is empty or holds a non-finite coordinate.
///
/// ```
/// use meshgnn_losses::metrics::hausdorff_distance;
/// let a = [[0.0, 0.0, 0.0], [3.0, 4.0, 0.0]];
/// let b = [[0.0, 0.0, 0.0]];
/// assert_eq!(hausdorff_distance(&a, &b)?, 5.0);
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn hausdorff_distance(a: &[[f32; 3]], b: &[[f32; 3]]) -> Result<f64> {
    check_points("first point set", a)?;
    check_points("second point set", b)?;
    let (tree_a, tree_b) = rayon::join(|| PointIndex::new(a), || PointIndex::new(b));
    let (f, r) = rayon::join(
        || directed_hausdorff(a, &tree_b),
        || directed_hausdorff(b, &tree_a),
    );
    Ok(f.max(r))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_is_zero_and_hand_case() {
        let a = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 2.0, 0.0]];
        assert_eq!(hausdorff_distance(&a, &a).unwrap(), 0.0);
        let b = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]];
        // (0,2,0) is 2 from b; every point of b is in a.
        assert_eq!(hausdorff_distance(&a, &b).unwrap(), 2.0);
        assert_eq!(hausdorff_distance(&b, &a).unwrap(), 2.0);
    }

    #[test]
    fn order_invariant() {
        let a = [[0.0, 0.0, 0.0], [1.0, 0.5, 0.0], [0.0, 2.0, 0.3]];
        let mut a2 = a;
        a2.reverse();
        let b = [[0.2, 0.1, 0.0], [1.0, 1.0, 1.0]];
        assert_eq!(
            hausdorff_distance(&a, &b).unwrap(),
            hausdorff_distance(&a2, &b).unwrap()
        );
    }
}
