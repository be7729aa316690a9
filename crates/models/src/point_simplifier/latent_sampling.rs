//! The point selector of thesis ch. 5.3.2: farthest point sampling in the projector's latent
//! space (Eldar, Lindenbaum, Porat & Zeevi 1997, "The farthest point strategy for progressive
//! image sampling", IEEE TIP; in a learned space as in the thesis), with a spatial
//! partition that makes it scale to millions of points.
//!
//! # The approximation
//! Exact FPS costs `N · M · C` (1M points to 5% in 64-d: ≈ 3·10¹² flops). When `N` exceeds
//! `cell_size`, the cloud is split by recursive median cuts along the longest axis of each
//! cell's bounding box (a balanced kd-tree) into cells of `cell_size/2 .. cell_size` points;
//! each cell gets a share of the target proportional to its size (largest-remainder rounding,
//! ties by cell order, so the shares sum exactly to the target) and runs exact latent FPS on
//! its own points, all cells in parallel. Cost `N · (M/N · cell_size) · C`, i.e. linear in N.
//! With one cell (`N ≤ cell_size`) the result is exact FPS, the sequence of
//! [`meshgnn_graph::farthest_point_sampling`] from the same seeded start (tested). The quality
//! cost is measured in `docs/pcsimplify_model.md`.
//!
//! The per-cell kernel is specialised for wide embeddings: the generic-dimension distance of
//! the graph crate sums its 64 squares in one dependent chain, this one in 8 independent lanes
//! that the compiler vectorises (≈ 8× faster at C = 64); cells are small, so each runs
//! single-threaded and the parallelism is across cells.
//!
//! # Conventions
//! - `latent: #N×C` row-major `f32` (detached embeddings: the selection carries no gradient);
//!   `positions: #N×3` only drive the partition.
//! - The start of each cell's FPS is drawn from `seed` (cell `c` uses
//!   `seed ^ c·0x9E37_79B9_7F4A_7C15`, then the first draw of `StdRng` in `0..n`, as
//!   [`meshgnn_graph::FpsStart::Seeded`]); the thesis starts FPS at a random point.
//! - Output: `target` distinct `u32` indices, grouped by cell, each cell's in FPS order.
//!   Deterministic for any thread count.

use rand::{Rng, SeedableRng, rngs::StdRng};
use rayon::prelude::*;
use std::ops::Range;

use crate::{Error, Result};

/// How the selector trades exactness for speed on large clouds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LatentSamplingOptions {
    /// Largest cell on which exact latent FPS runs; clouds up to this size are sampled
    /// exactly. Default 2048.
    pub cell_size: usize,
}

impl Default for LatentSamplingOptions {
    fn default() -> Self {
        Self { cell_size: 2048 }
    }
}

/// Spatial cells: balanced median cuts of `indices` along the longest axis until every cell
/// holds at most `cell_size` points. Deterministic (ties by index).
fn split_cells(positions: &[[f32; 3]], mut indices: Vec<u32>, cell_size: usize) -> Vec<Vec<u32>> {
    order_cells(positions, &mut indices, cell_size);
    let mut ranges = Vec::new();
    cell_ranges(0, indices.len(), cell_size, &mut ranges);
    ranges.into_iter().map(|r| indices[r].to_vec()).collect()
}

/// Reorders `indices` in place, cell after cell of [`split_cells`]' partition.
fn order_cells(positions: &[[f32; 3]], indices: &mut [u32], cell_size: usize) {
    if indices.len() <= cell_size {
        return;
    }
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in indices.iter().filter_map(|&i| positions.get(i as usize)) {
        for d in 0..3 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    let axis = (0..3)
        .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))
        .unwrap_or(0);
    let key = |i: u32| (positions.get(i as usize).map_or(0.0, |p| p[axis]), i);
    let mid = indices.len() / 2;
    indices.select_nth_unstable_by(mid, |&a, &b| {
        let (ka, kb) = (key(a), key(b));
        ka.0.total_cmp(&kb.0).then(ka.1.cmp(&kb.1))
    });
    let (left, right) = indices.split_at_mut(mid);
    rayon::join(
        || order_cells(positions, left, cell_size),
        || order_cells(positions, right, cell_size),
    );
}

/// The ranges of the cells of [`order_cells`] over `start..start + len`, in order.
fn cell_ranges(start: usize, len: usize, cell_size: usize, out: &mut Vec<Range<usize>>) {
    if len <= cell_size {
        out.push(start..start + len);
        return;
    }
    let mid = len / 2;
    cell_ranges(start, mid, cell_size, out);
    cell_ranges(start + mid, len - mid, cell_size, out);
}

/// Shares of `target` proportional to `sizes` (largest remainder, ties by position), each at
/// most its size; they sum to `target` (≤ Σ sizes).
fn proportional_shares(sizes: &[usize], target: usize) -> Vec<usize> {
    let total: usize = sizes.iter().sum();
    if total == 0 {
        return vec![0; sizes.len()];
    }
    let mut shares: Vec<usize> = sizes.iter().map(|&s| s * target / total).collect();
    let assigned: usize = shares.iter().sum();
    let mut order: Vec<(usize, usize)> = sizes
        .iter()
        .enumerate()
        .map(|(c, &s)| ((s * target) % total, c))
        .filter(|&(rem, _)| rem > 0)
        .collect();
    order.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
    for &(_, c) in order.iter().take(target - assigned) {
        if let Some(s) = shares.get_mut(c) {
            *s += 1;
        }
    }
    shares
}

/// Latent-space FPS of `target` of the N points with `latent: #N×channels` embeddings, exact up
/// to `options.cell_size` points and cell-partitioned beyond (module docs).
///
/// Errors when `channels == 0`, the lengths disagree, `target > N`, or a value is NaN.
///
/// ```
/// use meshgnn_models::point_simplifier::{LatentSamplingOptions, latent_farthest_point_sampling};
/// let pos: Vec<[f32; 3]> = (0..100).map(|i| [i as f32, 0.0, 0.0]).collect();
/// let latent: Vec<f32> = (0..100).map(|i| (i as f32).sin()).collect(); // 1-d embeddings
/// let opts = LatentSamplingOptions { cell_size: 16 };
/// let kept = latent_farthest_point_sampling(&latent, 1, &pos, 10, opts, 7)?;
/// assert_eq!(kept.len(), 10);
/// # Ok::<(), meshgnn_models::Error>(())
/// ```
pub fn latent_farthest_point_sampling(
    latent: &[f32],
    channels: usize,
    positions: &[[f32; 3]],
    target: usize,
    options: LatentSamplingOptions,
    seed: u64,
) -> Result<Vec<u32>> {
    let n = positions.len();
    if channels == 0 || latent.len() != n * channels {
        return Err(Error::Invalid {
            what: "latent embeddings".into(),
            reason: format!(
                "{} values for {n} points × {channels} channels",
                latent.len()
            ),
        });
    }
    if target > n {
        return Err(Error::Invalid {
            what: "target count".into(),
            reason: format!("cannot keep {target} of {n} points"),
        });
    }
    if options.cell_size == 0 {
        return Err(Error::Invalid {
            what: "cell_size".into(),
            reason: "must be at least 1".into(),
        });
    }
    if let Some(bad) = latent.iter().position(|x| !x.is_finite()) {
        return Err(Error::Invalid {
            what: format!("latent embedding of point {}", bad / channels),
            reason: "is not finite".into(),
        });
    }
    if n <= options.cell_size {
        return Ok(cell_fps(latent, channels, target, cell_seed(seed, 0)));
    }
    let cells = split_cells(positions, (0..n as u32).collect(), options.cell_size);
    let sizes: Vec<usize> = cells.iter().map(Vec::len).collect();
    let shares = proportional_shares(&sizes, target);
    let picked = cells
        .par_iter()
        .zip(shares.par_iter())
        .enumerate()
        .map(|(c, (cell, &share))| -> Result<Vec<u32>> {
            if share == 0 {
                return Ok(Vec::new());
            }
            let mut buf = Vec::with_capacity(cell.len() * channels);
            for &i in cell {
                let row = latent
                    .get(i as usize * channels..(i as usize + 1) * channels)
                    .unwrap_or(&[]);
                buf.extend_from_slice(row);
            }
            let local = cell_fps(&buf, channels, share, cell_seed(seed, c));
            Ok(local
                .into_iter()
                .filter_map(|j| cell.get(j as usize).copied())
                .collect())
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(picked.into_iter().flatten().collect())
}

/// `‖a − b‖²` in 8 independent lanes (vectorised), then a fixed-order lane sum.
#[inline]
fn squared_distance(a: &[f32], b: &[f32]) -> f32 {
    let (ca, ra) = a.as_chunks::<8>();
    let (cb, rb) = b.as_chunks::<8>();
    let mut acc = [0f32; 8];
    for (x, y) in ca.iter().zip(cb) {
        for l in 0..8 {
            let t = x[l] - y[l];
            acc[l] += t * t;
        }
    }
    for (x, y) in ra.iter().zip(rb) {
        let t = x - y;
        acc[0] += t * t;
    }
    ((acc[0] + acc[4]) + (acc[1] + acc[5])) + ((acc[2] + acc[6]) + (acc[3] + acc[7]))
}

/// Exact FPS of `m` of the rows of `rows: #n×c` (finite, `m ≤ n`) from a start drawn with
/// `seed`: ties to the smallest index, selected rows never repeated.
fn cell_fps(rows: &[f32], c: usize, m: usize, seed: u64) -> Vec<u32> {
    let n = rows.len() / c.max(1);
    if m == 0 || n == 0 {
        return Vec::new();
    }
    let mut current = StdRng::seed_from_u64(seed).random_range(0..n as u32) as usize;
    let mut dist = vec![f32::INFINITY; n];
    let mut selected = Vec::with_capacity(m);
    selected.push(current as u32);
    while selected.len() < m {
        if let Some(d) = dist.get_mut(current) {
            *d = -1.0;
        }
        let centre = rows.get(current * c..(current + 1) * c).unwrap_or(&[]);
        let mut best = (f32::NEG_INFINITY, usize::MAX);
        for (i, (d, p)) in dist.iter_mut().zip(rows.chunks_exact(c)).enumerate() {
            if *d < 0.0 {
                continue;
            }
            let s = squared_distance(p, centre);
            if s < *d {
                *d = s;
            }
            if *d > best.0 {
                best = (*d, i);
            }
        }
        if best.1 == usize::MAX {
            break;
        }
        current = best.1;
        selected.push(current as u32);
    }
    selected
}

/// The FPS start seed of cell `c`.
fn cell_seed(seed: u64, c: usize) -> u64 {
    seed ^ (c as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshgnn_graph::{FpsStart, farthest_point_sampling};

    fn random(n: usize, c: usize, seed: u64) -> (Vec<[f32; 3]>, Vec<f32>) {
        let mut rng = StdRng::seed_from_u64(seed);
        let pos = (0..n)
            .map(|_| [rng.random(), rng.random(), rng.random()])
            .collect();
        let lat = (0..n * c).map(|_| rng.random_range(-1.0..1.0)).collect();
        (pos, lat)
    }

    #[test]
    fn single_cell_equals_exact_latent_fps() {
        for (n, c, m, seed) in [(500, 8, 40, 9), (3000, 64, 100, 1), (50, 3, 50, 4)] {
            let (pos, lat) = random(n, c, seed);
            let opts = LatentSamplingOptions { cell_size: n };
            let got = latent_farthest_point_sampling(&lat, c, &pos, m, opts, seed).unwrap();
            let exact = farthest_point_sampling(&lat, c, m, FpsStart::Seeded(seed)).unwrap();
            assert_eq!(got, exact, "n {n} c {c}");
        }
    }

    #[test]
    fn cells_give_exact_count_of_distinct_indices_deterministically() {
        let (pos, lat) = random(5000, 4, 2);
        let opts = LatentSamplingOptions { cell_size: 300 };
        for target in [1, 17, 250, 4999, 5000] {
            let a = latent_farthest_point_sampling(&lat, 4, &pos, target, opts, 3).unwrap();
            assert_eq!(a.len(), target);
            let mut s = a.clone();
            s.sort_unstable();
            s.dedup();
            assert_eq!(s.len(), target);
            assert!(s.iter().all(|&i| (i as usize) < 5000));
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .build()
                .unwrap();
            let b = pool
                .install(|| latent_farthest_point_sampling(&lat, 4, &pos, target, opts, 3))
                .unwrap();
            assert_eq!(a, b);
        }
    }

    #[test]
    fn cells_are_balanced_and_shares_proportional() {
        let (pos, _) = random(1000, 1, 3);
        let cells = split_cells(&pos, (0..1000).collect(), 100);
        assert!(cells.iter().all(|c| (50..=100).contains(&c.len())));
        assert_eq!(cells.iter().map(Vec::len).sum::<usize>(), 1000);
        assert_eq!(proportional_shares(&[3, 3, 4], 5), vec![2, 1, 2]);
        assert_eq!(proportional_shares(&[10, 10], 20), vec![10, 10]);
        assert_eq!(proportional_shares(&[1, 1, 1], 2).iter().sum::<usize>(), 2);
    }

    #[test]
    fn bad_inputs_are_errors() {
        let (pos, mut lat) = random(10, 2, 4);
        let o = LatentSamplingOptions::default();
        assert!(latent_farthest_point_sampling(&lat, 2, &pos, 11, o, 0).is_err());
        assert!(latent_farthest_point_sampling(&lat, 3, &pos, 2, o, 0).is_err());
        lat[5] = f32::NAN;
        assert!(latent_farthest_point_sampling(&lat, 2, &pos, 2, o, 0).is_err());
    }
}
