//! Exact farthest point sampling (FPS) in any dimension: the point selector of the point-cloud
//! simplifier, which runs FPS on the 64-d latent features (thesis ch. 5.3.2), and the FPS
//! baseline of ch. 5-6 (Eldar et al. 1997, "The farthest point strategy for progressive image
//! sampling", IEEE TIP; as used by PointNet++, Qi et al. 2017, NeurIPS).
//!
//! # Conventions
//! - `points: #N×dim` flat row-major `f32`; the result is `k` distinct `u32` indices in the
//!   order selected; the first is the start.
//! - Squared distances are `f32` sums of `(a_d − b_d)²` in dimension order (for `dim = 3` the
//!   exact expression of [`crate::fast_farthest_point_sampling`], which returns the same
//!   sequence).
//! - Each step picks the point with the largest distance to the selected set; ties go to the
//!   smallest index. Selected points are never picked again, so when points repeat and every
//!   remaining distance is 0, the unselected points follow in index order: always `k` distinct
//!   indices.
//! - Deterministic: chunked parallel updates reduce with the same total order, so any thread
//!   count gives the same sequence.
//!
//! Cost O(N·k) time, O(N) memory; O(N·d) when only `d < k` distinct positions exist (once
//! every remaining distance is 0 the rest of the sequence is known: the unselected points in
//! index order).

use rand::{Rng, SeedableRng, rngs::StdRng};
use rayon::prelude::*;

use crate::{Error, Result};

/// Points per parallel work item of the distance update.
const CHUNK: usize = 8192;

/// Distance marking an already selected point; below any real squared distance.
pub(crate) const SELECTED: f32 = -1.0;

/// How FPS picks its first point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FpsStart {
    /// Start at this point index.
    Index(u32),
    /// Start at a point drawn uniformly with `StdRng::seed_from_u64(seed)`.
    Seeded(u64),
}

impl Default for FpsStart {
    /// Start at point 0 (as PyTorch3D and fpsample do by default).
    fn default() -> Self {
        Self::Index(0)
    }
}

impl FpsStart {
    /// The start index for a cloud of `n > 0` points.
    pub(crate) fn resolve(self, n: usize) -> Result<u32> {
        match self {
            Self::Index(i) if (i as usize) < n => Ok(i),
            Self::Index(i) => Err(Error::IndexOutOfRange {
                what: "FPS start point",
                index: i as usize,
                len: n,
            }),
            Self::Seeded(seed) => Ok(StdRng::seed_from_u64(seed).random_range(0..n as u32)),
        }
    }
}

/// Checks the arguments shared by the FPS variants; returns the point count.
pub(crate) fn check_fps_input(points: &[f32], dim: usize, k: usize) -> Result<usize> {
    if dim == 0 {
        return Err(Error::InvalidParameter {
            name: "dim",
            message: "must be at least 1".into(),
        });
    }
    if !points.len().is_multiple_of(dim) {
        return Err(Error::ShapeMismatch {
            what: "length of points (a multiple of dim)",
            expected: points.len() / dim * dim,
            actual: points.len(),
        });
    }
    let n = points.len() / dim;
    if u32::try_from(n).is_err() {
        return Err(Error::InvalidParameter {
            name: "points",
            message: format!("{n} points do not fit u32 indices"),
        });
    }
    if k > n {
        return Err(Error::InvalidParameter {
            name: "k",
            message: format!("cannot select {k} distinct points out of {n}"),
        });
    }
    if let Some(bad) = points.iter().position(|x| !x.is_finite()) {
        return Err(Error::NonFinite {
            what: "point",
            index: bad / dim,
        });
    }
    Ok(n)
}

/// `(distance, index)` with the larger distance first, ties to the smaller index.
#[inline]
pub(crate) fn better(a: (f32, u32), b: (f32, u32)) -> bool {
    a.0 > b.0 || (a.0 == b.0 && a.1 < b.1)
}

/// Lowers `dist` (a chunk of distances) to the squared distances of `pts` (the matching
/// points, flat) to `centre`, and returns the chunk's best `(distance, index)`, indices offset
/// by `base`. Two passes (update, then max and its first position) so each loop vectorises.
fn update_chunk(dist: &mut [f32], pts: &[f32], centre: &[f32], base: u32) -> (f32, u32) {
    if let [c0, c1, c2] = *centre {
        for (d, p) in dist.iter_mut().zip(pts.as_chunks::<3>().0) {
            let (x, y, z) = (p[0] - c0, p[1] - c1, p[2] - c2);
            let s = x * x + y * y + z * z;
            *d = if s < *d { s } else { *d };
        }
    } else {
        for (d, p) in dist.iter_mut().zip(pts.chunks_exact(centre.len())) {
            let mut s = 0.0f32;
            for (a, b) in p.iter().zip(centre) {
                let t = a - b;
                s += t * t;
            }
            *d = if s < *d { s } else { *d };
        }
    }
    let max = dist
        .iter()
        .fold(f32::NEG_INFINITY, |m, &d| if d > m { d } else { m });
    match dist.iter().position(|&d| d == max) {
        Some(i) => (max, base + i as u32),
        None => (f32::NEG_INFINITY, u32::MAX),
    }
}

/// Exact farthest point sampling of `k` of the `points: #N×dim` (flat, row-major): each pick
/// maximises the distance to those already picked. O(N·k), parallel, deterministic.
///
/// Errors when `dim == 0`, the length is not a multiple of `dim`, `k > N`, the start index is
/// out of range or a coordinate is NaN/infinite. `k == 0` gives an empty result.
///
/// ```
/// use meshgnn_graph::{FpsStart, farthest_point_sampling};
/// // Points on a line at 0, 1, 2, 10: start at 0, then 10, then 2 (farther from {0, 10} than 1).
/// let points = [0.0, 1.0, 2.0, 10.0];
/// let picked = farthest_point_sampling(&points, 1, 3, FpsStart::Index(0))?;
/// assert_eq!(picked, vec![0, 3, 2]);
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn farthest_point_sampling(
    points: &[f32],
    dim: usize,
    k: usize,
    start: FpsStart,
) -> Result<Vec<u32>> {
    let n = check_fps_input(points, dim, k)?;
    if k == 0 {
        return Ok(Vec::new());
    }
    let first = start.resolve(n)?;
    let mut distances = vec![f32::INFINITY; n];
    let mut selected = Vec::with_capacity(k);
    let mut current = first;
    selected.push(current);
    while selected.len() < k {
        let centre_at = current as usize * dim;
        let centre = &points[centre_at..centre_at + dim];
        distances[current as usize] = SELECTED;
        let best = distances
            .par_chunks_mut(CHUNK)
            .zip(points.par_chunks(CHUNK * dim))
            .enumerate()
            .map(|(c, (dist, pts))| update_chunk(dist, pts, centre, (c * CHUNK) as u32))
            .reduce(
                || (f32::NEG_INFINITY, u32::MAX),
                |a, b| if better(a, b) { a } else { b },
            );
        current = best.1;
        selected.push(current);
        if best.0 == 0.0 {
            // Every unselected point now coincides with a selected one: their distances stay 0
            // and ties go to the smallest index, so the rest follow in index order. One O(N)
            // pass instead of O(N) per pick on duplicate-heavy clouds.
            distances[current as usize] = SELECTED;
            let missing = k - selected.len();
            selected.extend(
                (0..n as u32)
                    .zip(&distances)
                    .filter(|&(_, &d)| d != SELECTED)
                    .map(|(i, _)| i)
                    .take(missing),
            );
        }
    }
    Ok(selected)
}

/// [`farthest_point_sampling`] of many clouds at once, parallel across clouds (the batch
/// dimension of the point-cloud simplifier): `clouds[b]: #N_b×dim`, `k` picks from each, all
/// with the same `start` rule. The result is one index list per cloud.
///
/// ```
/// use meshgnn_graph::{FpsStart, farthest_point_sampling_batch};
/// let a = [0.0, 1.0, 5.0];
/// let b = [2.0, 0.0, 9.0, 3.0];
/// let picked = farthest_point_sampling_batch(&[&a, &b], 1, 2, FpsStart::Index(0))?;
/// assert_eq!(picked, vec![vec![0, 2], vec![0, 2]]);
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn farthest_point_sampling_batch(
    clouds: &[&[f32]],
    dim: usize,
    k: usize,
    start: FpsStart,
) -> Result<Vec<Vec<u32>>> {
    clouds
        .par_iter()
        .map(|cloud| farthest_point_sampling(cloud, dim, k, start))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The textbook O(N·k) loop, sequential, in f64 on the same f32 distances.
    pub(crate) fn naive(points: &[f32], dim: usize, k: usize, start: u32) -> Vec<u32> {
        let n = points.len() / dim;
        let dist = |i: usize, j: usize| -> f32 {
            let mut s = 0.0f32;
            for d in 0..dim {
                let t = points[i * dim + d] - points[j * dim + d];
                s += t * t;
            }
            s
        };
        let mut chosen = vec![start];
        let mut min_d = vec![f32::INFINITY; n];
        while chosen.len() < k {
            let last = *chosen.last().unwrap() as usize;
            for (i, m) in min_d.iter_mut().enumerate() {
                *m = m.min(dist(i, last));
            }
            let next = (0..n)
                .filter(|i| !chosen.contains(&(*i as u32)))
                .fold(None, |best: Option<usize>, i| match best {
                    Some(b) if min_d[b] >= min_d[i] => Some(b),
                    _ => Some(i),
                })
                .unwrap();
            chosen.push(next as u32);
        }
        chosen
    }

    pub(crate) fn random_flat(seed: u64, n: usize, dim: usize) -> Vec<f32> {
        let mut rng = StdRng::seed_from_u64(seed);
        (0..n * dim).map(|_| rng.random_range(-1.0..1.0)).collect()
    }

    #[test]
    fn matches_naive_reference_in_3_and_64_dims() {
        for seed in 0..4 {
            for &(dim, n, k) in &[(3, 20_000, 60), (64, 3000, 40), (3, 50, 50)] {
                let pts = random_flat(seed, n, dim);
                let start = (seed as u32 * 7) % n as u32;
                let got = farthest_point_sampling(&pts, dim, k, FpsStart::Index(start)).unwrap();
                assert_eq!(got, naive(&pts, dim, k, start), "seed {seed} dim {dim}");
            }
        }
    }

    #[test]
    fn identical_points_are_sampled_in_linear_time() {
        // 200k copies of one point: after the start, index order. Without the shortcut this
        // is 10¹⁰ distance updates; with it, one pass.
        let n = 200_000;
        let pts: Vec<f32> = [0.5f32, -1.0, 2.0].repeat(n);
        let got = farthest_point_sampling(&pts, 3, n / 2, FpsStart::Index(7)).unwrap();
        let want: Vec<u32> = std::iter::once(7)
            .chain((0..n as u32).filter(|&i| i != 7))
            .take(n / 2)
            .collect();
        assert_eq!(got, want);
        // Two distinct positions (a collinear pair of clusters): both, then index order.
        let mut two = [0.0f32, 0.0, 0.0].repeat(n);
        two[3 * 5..3 * 6].copy_from_slice(&[4.0, 0.0, 0.0]);
        let got = farthest_point_sampling(&two, 3, 4, FpsStart::Index(0)).unwrap();
        assert_eq!(got, vec![0, 5, 1, 2]);
    }

    #[test]
    fn repeated_points_give_distinct_indices_in_index_order() {
        // Three distinct positions, each repeated; after them, remaining points in index order.
        let mut pts = Vec::new();
        for i in 0..12 {
            pts.extend_from_slice(&[(i % 3) as f32, 0.0, 0.0]);
        }
        let got = farthest_point_sampling(&pts, 3, 12, FpsStart::Index(4)).unwrap();
        assert_eq!(&got[..3], &[4, 0, 2]);
        assert_eq!(&got[3..], &[1, 3, 5, 6, 7, 8, 9, 10, 11]);
        let mut sorted = got.clone();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!(sorted.len(), 12);
    }

    #[test]
    fn same_result_for_one_and_two_threads() {
        let pts = random_flat(9, 40_000, 3);
        let run = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| farthest_point_sampling(&pts, 3, 200, FpsStart::Seeded(5)).unwrap())
        };
        assert_eq!(run(1), run(2));
    }

    #[test]
    fn batch_equals_individual_calls_and_seeded_start_is_reproducible() {
        let a = random_flat(1, 500, 64);
        let b = random_flat(2, 700, 64);
        let batch = farthest_point_sampling_batch(&[&a, &b], 64, 30, FpsStart::Seeded(3)).unwrap();
        assert_eq!(
            batch[0],
            farthest_point_sampling(&a, 64, 30, FpsStart::Seeded(3)).unwrap()
        );
        assert_eq!(
            batch[1],
            farthest_point_sampling(&b, 64, 30, FpsStart::Seeded(3)).unwrap()
        );
        assert_eq!(batch[0][0], FpsStart::Seeded(3).resolve(500).unwrap());
    }

    #[test]
    fn rejects_bad_input() {
        assert!(farthest_point_sampling(&[0.0; 6], 3, 3, FpsStart::Index(0)).is_err());
        assert!(farthest_point_sampling(&[0.0; 7], 3, 1, FpsStart::Index(0)).is_err());
        assert!(farthest_point_sampling(&[0.0; 6], 0, 1, FpsStart::Index(0)).is_err());
        assert!(farthest_point_sampling(&[0.0; 6], 3, 1, FpsStart::Index(2)).is_err());
        assert!(matches!(
            farthest_point_sampling(
                &[0.0, 0.0, 0.0, f32::NAN, 0.0, 0.0],
                3,
                1,
                FpsStart::Index(0)
            ),
            Err(Error::NonFinite { index: 1, .. })
        ));
        assert_eq!(
            farthest_point_sampling(&[], 3, 0, FpsStart::Index(0)).unwrap(),
            Vec::<u32>::new()
        );
    }
}
