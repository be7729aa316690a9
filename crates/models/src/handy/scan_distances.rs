//! Reconstruction-to-scan and scan-to-reconstruction distances, the fitting metrics of thesis
//! ch. 3.4.4, Table 3.5 (after LISA, Corona et al. 2022, CVPR).

use meshgnn_graph::knn_query;

use crate::Result;

/// Table 3.5 metrics between a fitted reconstruction and a scan, in input units (mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScanDistances {
    /// R2S: mean over reconstruction vertices of the distance to the nearest scan point.
    pub r2s: f64,
    /// S2R: mean over scan points of the distance to the nearest reconstruction vertex.
    pub s2r: f64,
}

/// Mean Euclidean nearest-neighbour distance from each of `from: #A×3` to `to: #B×3`
/// (k-d tree, O((A + B) log B)), accumulated in `f64` in index order.
fn mean_nearest_distance(from: &[[f32; 3]], to: &[[f32; 3]]) -> Result<f64> {
    let nn = knn_query(from, to, 1)?;
    let sum: f64 = nn
        .squared_distances
        .iter()
        .map(|&d| f64::from(d).sqrt())
        .sum();
    Ok(sum / from.len().max(1) as f64)
}

/// Table 3.5: R2S and S2R between `reconstruction: #V×3` (the fitted model's vertices) and
/// `scan: #P×3`, as vertex-to-point distances like the thesis. Fails on an empty or
/// non-finite input.
///
/// ```
/// use meshgnn_models::scan_distances;
/// let rec = [[0.0, 0.0, 0.0], [4.0, 0.0, 0.0]];
/// let scan = [[0.0, 0.0, 1.0]];
/// let d = scan_distances(&rec, &scan)?;
/// assert!((d.s2r - 1.0).abs() < 1e-9);
/// assert!((d.r2s - (1.0 + 17f64.sqrt()) / 2.0).abs() < 1e-6);
/// # Ok::<(), meshgnn_models::Error>(())
/// ```
pub fn scan_distances(reconstruction: &[[f32; 3]], scan: &[[f32; 3]]) -> Result<ScanDistances> {
    Ok(ScanDistances {
        r2s: mean_nearest_distance(reconstruction, scan)?,
        s2r: mean_nearest_distance(scan, reconstruction)?,
    })
}
