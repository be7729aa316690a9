//! How many edge pairs of two triangles cross? `m_e` of thesis eq. 6.12.

use crate::predicates::segments_cross::segments_cross;

/// Number of the nine (edge of `t`, edge of `u`) pairs that cross properly in 3-d (coplanar
/// and each strictly splitting the other, see [`super::segments_cross`]). A shared edge or
/// shared vertex is not a crossing, so mesh neighbours score 0.
///
/// ```
/// use meshgnn_losses::predicates::edge_crossing_count;
/// let t = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]];
/// let shifted = [[0.5, 0.5, 0.0], [2.5, 0.5, 0.0], [0.5, 2.5, 0.0]];
/// assert_eq!(edge_crossing_count(&t, &shifted), 2);
/// ```
pub fn edge_crossing_count(t: &[[f32; 3]; 3], u: &[[f32; 3]; 3]) -> usize {
    let mut count = 0;
    for i in 0..3 {
        for j in 0..3 {
            if segments_cross(&t[i], &t[(i + 1) % 3], &u[j], &u[(j + 1) % 3]) {
                count += 1;
            }
        }
    }
    count
}
