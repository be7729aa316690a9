//! Fast exact farthest point sampling of 3-d points with a kd-tree of bounded boxes, after
//! QuickFPS (Han, Wang, Li & Liu 2023, "QuickFPS: Architecture and algorithm co-design for
//! farthest point sampling in large-scale point clouds", IEEE TCAD) and the bucket-based FPS of
//! the `fpsample` package: same result as [`crate::farthest_point_sampling`], far less work.
//!
//! # How
//! Every kd-tree node keeps the largest current distance of its points (with its index). When a
//! point `s` is selected, a node is skipped when the squared distance from `s` to its box is at
//! least that maximum: no point inside can get closer to `s` than to the set already selected,
//! so none of its distances changes. Skipping is exact because the box bound never exceeds the
//! computed distance of a point inside (see [`meshgnn_geometry::SpatialIndex`]'s notes), and distances use the
//! very expression of the exact version. The next point is the root's maximum.
//!
//! # Conventions
//! Identical to [`crate::farthest_point_sampling`]: `points: #N×3`, `k` distinct `u32` indices
//! in selection order, ties to the smallest index, selected points never repeated (so repeated
//! positions still give `k` distinct indices), deterministic. Proven equal to the exact
//! version in the tests (uniform, clustered and duplicated sets, several starts).
//!
//! Cost: O(N log N) to build the tree, then each step visits only the nodes whose box is nearer
//! to the new point than their current maximum (a neighbourhood that shrinks as sampling
//! proceeds), single-threaded per cloud; [`fast_farthest_point_sampling_batch`] runs clouds in
//! parallel. Memory: about 24 bytes per point plus the tree. Measured against exact FPS and
//! fpsample in `docs/graph.md`.

use meshgnn_geometry::{SpatialIndex, box_squared_distance, squared_distance};
use rayon::prelude::*;

use crate::Result;
use crate::farthest_point_sampling::{FpsStart, SELECTED, better, check_fps_input};

/// Leaf size of the tree: points rescanned when a leaf is touched vs nodes visited (not tuned).
const LEAF_SIZE: usize = 32;

/// Mutable FPS state over the tree.
struct FpsState<'a> {
    tree: &'a SpatialIndex,
    /// Current distance of each reordered point to the selected set.
    dist: Vec<f32>,
    /// Per node: largest `(distance, index)` of its points, ties to the smaller index.
    node_max: Vec<(f32, u32)>,
    /// Per reordered point: position in the selection of its nearest selected point.
    owner: Vec<u32>,
}

impl FpsState<'_> {
    /// Lowers the distances of the points of `node` that are closer to `q` (at slot `slot`,
    /// whose own distance was just set to [`SELECTED`]) and refreshes the node maxima.
    fn update(&mut self, node: usize, q: &[f32; 3], slot: u32, position: u32) {
        let nd = self.tree.nodes()[node];
        let contains = nd.start <= slot && slot < nd.end;
        if !contains && box_squared_distance(q, &nd.lo, &nd.hi) >= self.node_max[node].0 {
            return;
        }
        if node >= self.tree.first_leaf() {
            let (s, e) = (nd.start as usize, nd.end as usize);
            let mut best = (f32::NEG_INFINITY, u32::MAX);
            for (((p, d), o), &id) in self.tree.slot_points()[s..e]
                .iter()
                .zip(&mut self.dist[s..e])
                .zip(&mut self.owner[s..e])
                .zip(&self.tree.slot_ids()[s..e])
            {
                let nd2 = squared_distance(p, q);
                if nd2 < *d {
                    *d = nd2;
                    *o = position;
                }
                if better((*d, id), best) {
                    best = (*d, id);
                }
            }
            self.node_max[node] = best;
            return;
        }
        let (l, r) = (2 * node + 1, 2 * node + 2);
        self.update(l, q, slot, position);
        self.update(r, q, slot, position);
        let (a, b) = (self.node_max[l], self.node_max[r]);
        self.node_max[node] = if better(a, b) { a } else { b };
    }
}

/// Farthest point sampling of `k` of the `points: #N×3`, exactly as
/// [`crate::farthest_point_sampling`] (same sequence from the same start) but pruned with a
/// kd-tree: use it for large clouds. Thesis ch. 5 and 6 use FPS as the sampling baseline.
///
/// Errors as [`crate::farthest_point_sampling`]: `k > N`, a bad start index, NaN/infinite
/// coordinates. `k == 0` gives an empty result.
///
/// ```
/// use meshgnn_graph::{FpsStart, fast_farthest_point_sampling, farthest_point_sampling};
/// let points: Vec<[f32; 3]> = (0..1000)
///     .map(|i| { let t = i as f32 * 0.1; [t.cos(), t.sin(), t * 0.01] })
///     .collect();
/// let fast = fast_farthest_point_sampling(&points, 50, FpsStart::Index(0))?;
/// let exact = farthest_point_sampling(points.as_flattened(), 3, 50, FpsStart::Index(0))?;
/// assert_eq!(fast, exact);
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn fast_farthest_point_sampling(
    points: &[[f32; 3]],
    k: usize,
    start: FpsStart,
) -> Result<Vec<u32>> {
    Ok(fast_farthest_point_sampling_with_owners(points, k, start)?.0)
}

/// [`fast_farthest_point_sampling`], and for every input point the position in the selection of
/// its nearest selected point (ties to the earlier one, as [`SpatialIndex::knn`] orders them;
/// a selected point owns itself unless an earlier one coincides with it): the Voronoi
/// assignment FPS has computed by its last step, which [`crate::centroidal_relaxation_indexed`]
/// takes instead of a k-NN pass of its own. `(indices: #k, owners: #N)`.
///
/// ```
/// use meshgnn_graph::{FpsStart, fast_farthest_point_sampling_with_owners};
/// let points = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [5.0, 0.0, 0.0], [6.0, 0.0, 0.0]];
/// let (kept, owners) = fast_farthest_point_sampling_with_owners(&points, 2, FpsStart::Index(0))?;
/// assert_eq!(kept, vec![0, 3]);
/// assert_eq!(owners, vec![0, 0, 1, 1]);
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn fast_farthest_point_sampling_with_owners(
    points: &[[f32; 3]],
    k: usize,
    start: FpsStart,
) -> Result<(Vec<u32>, Vec<u32>)> {
    check_fps_input(points.as_flattened(), 3, k)?;
    let tree = SpatialIndex::with_leaf_size(points, LEAF_SIZE)?;
    fast_farthest_point_sampling_indexed(&tree, k, start)
}

/// [`fast_farthest_point_sampling_with_owners`] over the points of a [`SpatialIndex`] built
/// for other queries too (one tree per cloud: the point simplifier's k-NN index): the same
/// result whatever the index's leaf size. Errors as [`fast_farthest_point_sampling`].
///
/// ```
/// use meshgnn_geometry::SpatialIndex;
/// use meshgnn_graph::{FpsStart, fast_farthest_point_sampling_indexed};
/// let points = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [5.0, 0.0, 0.0], [6.0, 0.0, 0.0]];
/// let index = SpatialIndex::new(&points)?;
/// let (kept, owners) = fast_farthest_point_sampling_indexed(&index, 2, FpsStart::Index(0))?;
/// assert_eq!((kept, owners), (vec![0, 3], vec![0, 0, 1, 1]));
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn fast_farthest_point_sampling_indexed(
    tree: &SpatialIndex,
    k: usize,
    start: FpsStart,
) -> Result<(Vec<u32>, Vec<u32>)> {
    let n = check_fps_input(tree.slot_points().as_flattened(), 3, k)?;
    if k == 0 {
        return Ok((Vec::new(), vec![0; n]));
    }
    let first = start.resolve(n)?;
    let mut slot_of = vec![0u32; n];
    for (slot, &id) in tree.slot_ids().iter().enumerate() {
        slot_of[id as usize] = slot as u32;
    }
    let mut state = FpsState {
        tree,
        dist: vec![f32::INFINITY; n],
        // an empty node (a leaf of a tree with leaf size 1) never wins; the others start
        // unvisited, above every distance
        node_max: tree
            .nodes()
            .iter()
            .map(|nd| match nd.start == nd.end {
                true => (f32::NEG_INFINITY, u32::MAX),
                false => (f32::INFINITY, 0),
            })
            .collect(),
        owner: vec![0; n],
    };
    let mut selected = Vec::with_capacity(k);
    let mut current = first;
    selected.push(current);
    loop {
        let position = (selected.len() - 1) as u32;
        let slot = slot_of[current as usize] as usize;
        // a selected point coinciding with an earlier one stays that one's (distance 0, tie)
        if state.dist[slot] != 0.0 {
            state.owner[slot] = position;
        }
        state.dist[slot] = SELECTED;
        let q = tree.slot_points()[slot];
        state.update(0, &q, slot as u32, position);
        if selected.len() == k {
            break;
        }
        current = state.node_max[0].1;
        selected.push(current);
    }
    let mut owners = vec![0u32; n];
    for (&id, &o) in tree.slot_ids().iter().zip(&state.owner) {
        owners[id as usize] = o;
    }
    Ok((selected, owners))
}

/// [`fast_farthest_point_sampling`] of many clouds, parallel across clouds: `clouds[b]: #N_b×3`,
/// `k` picks from each with the same `start` rule.
///
/// ```
/// use meshgnn_graph::{FpsStart, fast_farthest_point_sampling_batch};
/// let a = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [5.0, 0.0, 0.0]];
/// let b = [[0.0, 2.0, 0.0], [0.0, 0.0, 0.0], [0.0, 9.0, 0.0]];
/// let picked = fast_farthest_point_sampling_batch(&[&a, &b], 2, FpsStart::Index(0))?;
/// assert_eq!(picked, vec![vec![0, 2], vec![0, 2]]);
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn fast_farthest_point_sampling_batch(
    clouds: &[&[[f32; 3]]],
    k: usize,
    start: FpsStart,
) -> Result<Vec<Vec<u32>>> {
    clouds
        .par_iter()
        .map(|cloud| fast_farthest_point_sampling(cloud, k, start))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::farthest_point_sampling;
    use rand::{Rng, SeedableRng, rngs::StdRng};

    fn uniform(seed: u64, n: usize) -> Vec<[f32; 3]> {
        let mut rng = StdRng::seed_from_u64(seed);
        (0..n)
            .map(|_| [rng.random(), rng.random(), rng.random()])
            .collect()
    }

    /// Tight Gaussian-like clusters of very different sizes.
    fn clustered(seed: u64, n: usize) -> Vec<[f32; 3]> {
        let mut rng = StdRng::seed_from_u64(seed);
        let centres: Vec<[f32; 3]> = (0..6)
            .map(|_| [rng.random(), rng.random(), rng.random()])
            .collect();
        (0..n)
            .map(|i| {
                let c = centres[i % 6];
                let spread = 10f32.powi(-((i % 6) as i32) - 1);
                [
                    c[0] + spread * rng.random_range(-1.0..1.0),
                    c[1] + spread * rng.random_range(-1.0..1.0),
                    c[2] + spread * rng.random_range(-1.0..1.0),
                ]
            })
            .collect()
    }

    /// Few distinct positions (a coarse grid), each repeated many times.
    fn duplicated(seed: u64, n: usize) -> Vec<[f32; 3]> {
        let mut rng = StdRng::seed_from_u64(seed);
        (0..n)
            .map(|_| {
                [
                    rng.random_range(0..6) as f32,
                    rng.random_range(0..5) as f32,
                    rng.random_range(0..2) as f32,
                ]
            })
            .collect()
    }

    fn exact(points: &[[f32; 3]], k: usize, start: FpsStart) -> Vec<u32> {
        farthest_point_sampling(points.as_flattened(), 3, k, start).unwrap()
    }

    #[test]
    fn equals_exact_fps_on_uniform_clustered_and_duplicated_sets() {
        for seed in 0..3 {
            for (name, pts) in [
                ("uniform", uniform(seed, 20_000)),
                ("clustered", clustered(seed, 20_000)),
                ("duplicated", duplicated(seed, 5_000)),
            ] {
                for (k, start) in [(500, FpsStart::Index(0)), (2000, FpsStart::Seeded(seed))] {
                    let k = k.min(pts.len());
                    let fast = fast_farthest_point_sampling(&pts, k, start).unwrap();
                    assert_eq!(fast, exact(&pts, k, start), "{name} seed {seed} k {k}");
                }
            }
        }
    }

    #[test]
    fn a_shared_index_of_any_leaf_size_gives_the_same_selection_and_owners() {
        for pts in [uniform(4, 6000), clustered(5, 6000), duplicated(6, 3000)] {
            let want =
                fast_farthest_point_sampling_with_owners(&pts, 700, FpsStart::Seeded(1)).unwrap();
            for leaf in [1, 16, 100] {
                let index = SpatialIndex::with_leaf_size(&pts, leaf).unwrap();
                let got =
                    fast_farthest_point_sampling_indexed(&index, 700, FpsStart::Seeded(1)).unwrap();
                assert_eq!(got, want, "leaf {leaf}");
            }
        }
        let index = SpatialIndex::new(&uniform(1, 10)).unwrap();
        assert!(fast_farthest_point_sampling_indexed(&index, 11, FpsStart::Index(0)).is_err());
    }

    #[test]
    fn selects_every_point_of_small_and_repeated_clouds() {
        let pts = duplicated(7, 300);
        let fast = fast_farthest_point_sampling(&pts, 300, FpsStart::Index(5)).unwrap();
        assert_eq!(fast, exact(&pts, 300, FpsStart::Index(5)));
        let mut sorted = fast;
        sorted.sort_unstable();
        assert_eq!(sorted, (0..300).collect::<Vec<u32>>());
        let one = [[1.0f32, 2.0, 3.0]];
        assert_eq!(
            fast_farthest_point_sampling(&one, 1, FpsStart::Index(0)).unwrap(),
            vec![0]
        );
    }

    #[test]
    fn batch_matches_single_calls_and_errors_are_reported() {
        let (a, b) = (uniform(1, 3000), clustered(2, 4000));
        let batch = fast_farthest_point_sampling_batch(&[&a, &b], 100, FpsStart::Index(3)).unwrap();
        assert_eq!(batch[0], exact(&a, 100, FpsStart::Index(3)));
        assert_eq!(batch[1], exact(&b, 100, FpsStart::Index(3)));
        assert!(fast_farthest_point_sampling(&a, 3001, FpsStart::Index(0)).is_err());
        assert!(fast_farthest_point_sampling(&a, 10, FpsStart::Index(3000)).is_err());
        let nan = [[0.0f32; 3], [f32::NAN, 0.0, 0.0]];
        assert!(fast_farthest_point_sampling(&nan, 1, FpsStart::Index(0)).is_err());
    }

    #[test]
    fn identical_and_collinear_clouds_of_200k_points() {
        let n = 200_000;
        let same = vec![[1.0f32, 2.0, 3.0]; n];
        let got = fast_farthest_point_sampling(&same, 1000, FpsStart::Index(3)).unwrap();
        let want: Vec<u32> = std::iter::once(3)
            .chain((0..n as u32).filter(|&i| i != 3))
            .take(1000)
            .collect();
        assert_eq!(got, want);
        // A line: the far end, then the middle (tied with its right neighbour: smaller index).
        let line: Vec<[f32; 3]> = (0..n).map(|i| [i as f32, 0.0, 0.0]).collect();
        let got = fast_farthest_point_sampling(&line, 5, FpsStart::Index(0)).unwrap();
        assert_eq!(got[..3], [0, 199_999, 99_999]);
        assert_eq!(got, exact(&line, 5, FpsStart::Index(0)));
    }
}
