//! The order of points along a 3D Hilbert curve over their bounding box: points near each
//! other on the curve are near each other in space. Used to spread draws
//! ([`crate::balanced_sampling`]) and to lay points out in memory so that a point's
//! neighbours sit close to it (graph layers read every neighbour's row).

use rayon::prelude::*;

/// Bits per axis of the curve's grid.
const CURVE_BITS: u32 = 16;

/// The index along a 3D Hilbert curve of the grid cell `cell` (each `< 2^CURVE_BITS`):
/// Skilling's transpose algorithm ("Programming the Hilbert curve", AIP Conf. Proc. 707, 2004),
/// then the transposed bits interleaved.
fn hilbert_index(mut x: [u32; 3]) -> u64 {
    let top = 1u32 << (CURVE_BITS - 1);
    // Inverse undo of the excess work.
    let mut q = top;
    while q > 1 {
        let p = q - 1;
        for i in 0..3 {
            if x[i] & q != 0 {
                x[0] ^= p;
            } else {
                let t = (x[0] ^ x[i]) & p;
                x[0] ^= t;
                x[i] ^= t;
            }
        }
        q >>= 1;
    }
    // Gray encode.
    for i in 1..3 {
        x[i] ^= x[i - 1];
    }
    let mut t = 0;
    let mut q = top;
    while q > 1 {
        if x[2] & q != 0 {
            t ^= q - 1;
        }
        q >>= 1;
    }
    for v in &mut x {
        *v ^= t;
    }
    let mut index = 0u64;
    for bit in (0..CURVE_BITS).rev() {
        for v in x {
            index = (index << 1) | u64::from((v >> bit) & 1);
        }
    }
    index
}

/// The points' order along the Hilbert curve over their bounding box (ties by index):
/// `order[r]` is the index of the `r`-th point along the curve. Non-finite coordinates
/// land in an arbitrary cell.
///
/// ```
/// use meshgnn_graph::hilbert_order;
/// let line = [[3.0f32, 0.0, 0.0], [0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [1.0, 0.0, 0.0]];
/// let order = hilbert_order(&line);
/// let xs: Vec<f32> = order.iter().map(|&i| line[i as usize][0]).collect();
/// assert!(xs == [0.0, 1.0, 2.0, 3.0] || xs == [3.0, 2.0, 1.0, 0.0]);
/// ```
pub fn hilbert_order(points: &[[f32; 3]]) -> Vec<u32> {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in points {
        for c in 0..3 {
            lo[c] = lo[c].min(p[c]);
            hi[c] = hi[c].max(p[c]);
        }
    }
    let extent = (0..3).map(|c| hi[c] - lo[c]).fold(0.0f32, f32::max);
    let scale = if extent > 0.0 {
        f64::from((1u32 << CURVE_BITS) - 1) / f64::from(extent)
    } else {
        0.0
    };
    // Every key is distinct (the index breaks ties), so the parallel sort is deterministic.
    let mut keyed: Vec<(u64, u32)> = points
        .par_iter()
        .enumerate()
        .map(|(i, p)| {
            let cell = [0, 1, 2].map(|c| (f64::from(p[c] - lo[c]) * scale) as u32);
            (hilbert_index(cell), i as u32)
        })
        .collect();
    keyed.par_sort_unstable();
    keyed.into_par_iter().map(|(_, i)| i).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hilbert_neighbours_are_grid_neighbours() {
        // On a 4×4×4 corner of the grid the curve visits every cell once, each step to an
        // adjacent cell.
        let mut cells: Vec<(u64, [u32; 3])> = Vec::new();
        for x in 0..4 {
            for y in 0..4 {
                for z in 0..4 {
                    cells.push((hilbert_index([x, y, z]), [x, y, z]));
                }
            }
        }
        cells.sort_unstable();
        assert_eq!(cells[0].0, 0);
        for w in cells.windows(2) {
            assert_eq!(w[1].0, w[0].0 + 1);
            let d: u32 = (0..3).map(|c| w[0].1[c].abs_diff(w[1].1[c])).sum();
            assert_eq!(d, 1, "{:?} -> {:?}", w[0], w[1]);
        }
    }

    #[test]
    fn every_point_appears_once_and_ties_keep_index_order() {
        let points = [
            [1.0f32, 1.0, 1.0],
            [0.0, 0.0, 0.0],
            [1.0, 1.0, 1.0],
            [0.5, 0.2, 0.9],
        ];
        let mut order = hilbert_order(&points);
        let first_tie = order.iter().position(|&i| i == 0).unwrap();
        assert!(order.iter().position(|&i| i == 2).unwrap() > first_tie);
        order.sort_unstable();
        assert_eq!(order, vec![0, 1, 2, 3]);
        assert!(hilbert_order(&[]).is_empty());
    }
}
