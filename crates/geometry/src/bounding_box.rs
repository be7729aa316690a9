//! The axis-aligned bounding box of a point set and its diagonal: the scale that distances
//! are reported relative to (R2S/S2R of a scan fit, the QEM error of the speed example).

/// `(min, max)` corners of the axis-aligned box of `points`; `None` when there are none.
///
/// ```
/// use meshgnn_geometry::{bounding_box, bounding_box_diagonal};
/// let points = [[0.0, 1.0, 2.0], [3.0, -3.0, 2.0]];
/// assert_eq!(bounding_box(&points), Some(([0.0, -3.0, 2.0], [3.0, 1.0, 2.0])));
/// assert_eq!(bounding_box_diagonal(&points), 5.0);
/// ```
pub fn bounding_box(points: &[[f32; 3]]) -> Option<([f32; 3], [f32; 3])> {
    let first = *points.first()?;
    Some(points.iter().fold((first, first), |(lo, hi), p| {
        (
            std::array::from_fn(|k| lo[k].min(p[k])),
            std::array::from_fn(|k| hi[k].max(p[k])),
        )
    }))
}

/// Length of the bounding box's diagonal (0 for no points or one point).
pub fn bounding_box_diagonal(points: &[[f32; 3]]) -> f64 {
    bounding_box(points).map_or(0.0, |(lo, hi)| {
        (0..3)
            .map(|k| (f64::from(hi[k]) - f64::from(lo[k])).powi(2))
            .sum::<f64>()
            .sqrt()
    })
}
