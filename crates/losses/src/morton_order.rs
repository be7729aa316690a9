//! A spatially coherent visiting order for nearest-neighbour queries.
//!
//! Querying a k-d tree with points in random order touches a different part of the tree on
//! every query; visiting them along a Morton (Z-order) curve makes consecutive queries land in
//! the same leaves, so the tree stays in cache. Used by the Chamfer and Hausdorff metrics.

use rayon::prelude::*;

/// Spreads the low 21 bits of `x` to every third bit.
fn spread(x: u64) -> u64 {
    let mut x = x & 0x1f_ffff;
    x = (x | (x << 32)) & 0x1f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x1f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

/// Indices of `points: #P×3` sorted by their 63-bit Morton code in the points' bounding box
/// (ties by index, so the order is deterministic). Non-finite coordinates map to cell 0.
pub(crate) fn morton_order(points: &[[f32; 3]]) -> Vec<u32> {
    let (lo, hi) = points.iter().fold(
        ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]),
        |(lo, hi), p| {
            (
                [0, 1, 2].map(|i| lo[i].min(p[i])),
                [0, 1, 2].map(|i| hi[i].max(p[i])),
            )
        },
    );
    let scale = [0, 1, 2].map(|i| {
        let extent = f64::from(hi[i]) - f64::from(lo[i]);
        if extent > 0.0 {
            2_097_151.0 / extent
        } else {
            0.0
        }
    });
    let mut keyed: Vec<(u64, u32)> = points
        .par_iter()
        .enumerate()
        .map(|(i, p)| {
            let cell = |k: usize| -> u64 {
                let t = (f64::from(p[k]) - f64::from(lo[k])) * scale[k];
                if t.is_finite() {
                    t.clamp(0.0, 2_097_151.0) as u64
                } else {
                    0
                }
            };
            let code = spread(cell(0)) | (spread(cell(1)) << 1) | (spread(cell(2)) << 2);
            (code, i as u32)
        })
        .collect();
    keyed.par_sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn is_a_permutation_in_z_order() {
        let pts = [
            [1.0, 1.0, 1.0],
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        assert_eq!(morton_order(&pts), vec![1, 2, 3, 0]);
        assert_eq!(spread(0b11), 0b1001);
    }
}
