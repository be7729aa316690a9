//! A static, count-balanced 3-d kd-tree: the spatial index behind [`crate::knn_graph`],
//! [`crate::radius_graph`], [`crate::triangle_knn_graph`] and
//! [`crate::fast_farthest_point_sampling`].
//!
//! Why not kiddo: kiddo's trees split by coordinate value, so more than one bucket of
//! coincident points (common in scans and welded meshes) trips a debug assertion in the
//! immutable tree and a panic in the mutable one, and neither breaks distance ties by index.
//! This tree splits by *count* (median of `(coordinate, index)`, a total order), so any input,
//! duplicates included, gives a balanced tree, and queries order neighbours by
//! `(squared distance, index)`: deterministic on ties.
//!
//! # Layout
//! Heap order: node `i` has children `2i+1`, `2i+2`; all leaves are at the same depth and hold
//! between `leaf_size/2` and `leaf_size` points (fewer only when the cloud is smaller). Points
//! are stored reordered, leaf by leaf, with their original indices.
//!
//! # Exactness
//! Squared distances are computed as `dx·dx + dy·dy + dz·dz` in `f32`, left to right, everywhere
//! in the crate. The box lower bound uses the same expression on per-axis gaps; since float
//! subtraction and multiplication are monotonic, the bound never exceeds the computed distance
//! of any point in the box, so pruning with it is exact, not approximate.

use rayon::prelude::*;

/// `|a − b|²` in `f32`, in the one evaluation order the crate uses.
#[inline]
pub(crate) fn squared_distance(a: &[f32; 3], b: &[f32; 3]) -> f32 {
    let dx = a[0] - b[0];
    let dy = a[1] - b[1];
    let dz = a[2] - b[2];
    dx * dx + dy * dy + dz * dz
}

/// The squared distance from `q` to the box `[lo, hi]`: a lower bound of
/// [`squared_distance`] to any point inside it.
#[inline]
pub(crate) fn box_lower_bound(q: &[f32; 3], lo: &[f32; 3], hi: &[f32; 3]) -> f32 {
    let gap = |a: usize| {
        if q[a] < lo[a] {
            lo[a] - q[a]
        } else if q[a] > hi[a] {
            q[a] - hi[a]
        } else {
            0.0
        }
    };
    let (gx, gy, gz) = (gap(0), gap(1), gap(2));
    gx * gx + gy * gy + gz * gz
}

/// One node: its bounding box and its range in the reordered point arrays.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Node {
    pub lo: [f32; 3],
    pub hi: [f32; 3],
    pub start: u32,
    pub end: u32,
}

/// The tree. See the module docs.
#[derive(Debug, Clone)]
pub(crate) struct KdTree {
    /// Reordered points, `#P`.
    pub points: Vec<[f32; 3]>,
    /// Original index of each reordered point, `#P`.
    pub ids: Vec<u32>,
    /// Nodes in heap order.
    pub nodes: Vec<Node>,
    /// Index of the first leaf in `nodes` (leaves are `first_leaf..nodes.len()`).
    pub first_leaf: usize,
}

/// Subtrees smaller than this are partitioned on the current thread.
const PARALLEL_PARTITION: usize = 1 << 14;

impl KdTree {
    /// Builds the tree over `points: #P×3` (finite, checked by callers; `#P < 2³²`).
    /// O(P log P), parallel, deterministic.
    pub fn new(points: &[[f32; 3]], leaf_size: usize) -> Self {
        let leaf_size = leaf_size.max(1);
        let n = points.len();
        let mut depth = 0usize;
        while n.div_ceil(1 << depth) > leaf_size && depth < 40 {
            depth += 1;
        }
        let mut items: Vec<([f32; 3], u32)> = points
            .par_iter()
            .enumerate()
            .map(|(i, &p)| (p, i as u32))
            .collect();
        partition(&mut items, depth);
        let (points, ids): (Vec<[f32; 3]>, Vec<u32>) = items.into_par_iter().unzip();

        let node_count = (1usize << (depth + 1)) - 1;
        let first_leaf = (1usize << depth) - 1;
        let mut nodes = vec![
            Node {
                lo: [f32::INFINITY; 3],
                hi: [f32::NEG_INFINITY; 3],
                start: 0,
                end: 0,
            };
            node_count
        ];
        // Ranges top-down (the same halving rule as `partition`).
        if let Some(root) = nodes.first_mut() {
            root.end = n as u32;
        }
        for i in 0..first_leaf {
            let (s, e) = (nodes[i].start, nodes[i].end);
            let mid = s + (e - s) / 2;
            nodes[2 * i + 1].start = s;
            nodes[2 * i + 1].end = mid;
            nodes[2 * i + 2].start = mid;
            nodes[2 * i + 2].end = e;
        }
        // Boxes bottom-up: leaves in parallel, then unions.
        nodes[first_leaf..].par_iter_mut().for_each(|node| {
            for p in &points[node.start as usize..node.end as usize] {
                for ((lo, hi), &x) in node.lo.iter_mut().zip(node.hi.iter_mut()).zip(p) {
                    *lo = lo.min(x);
                    *hi = hi.max(x);
                }
            }
        });
        for i in (0..first_leaf).rev() {
            let (l, r) = (nodes[2 * i + 1], nodes[2 * i + 2]);
            for a in 0..3 {
                nodes[i].lo[a] = l.lo[a].min(r.lo[a]);
                nodes[i].hi[a] = l.hi[a].max(r.hi[a]);
            }
        }
        Self {
            points,
            ids,
            nodes,
            first_leaf,
        }
    }

    /// The `k` nearest points to `q` ordered by `(squared distance, index)`, skipping original
    /// index `exclude`; fewer when the tree holds fewer. Results go to `out` (cleared).
    pub fn nearest(&self, q: &[f32; 3], k: usize, exclude: Option<u32>, out: &mut Vec<(f32, u32)>) {
        out.clear();
        if k == 0 || self.points.is_empty() {
            return;
        }
        self.nearest_in(0, q, k, exclude, out);
    }

    fn nearest_in(
        &self,
        node: usize,
        q: &[f32; 3],
        k: usize,
        exclude: Option<u32>,
        out: &mut Vec<(f32, u32)>,
    ) {
        if node >= self.first_leaf {
            let nd = self.nodes[node];
            let (s, e) = (nd.start as usize, nd.end as usize);
            for (p, &id) in self.points[s..e].iter().zip(&self.ids[s..e]) {
                if Some(id) == exclude {
                    continue;
                }
                let d = squared_distance(p, q);
                let candidate = (d, id);
                if out.len() == k {
                    match out.last() {
                        Some(&worst) if less(candidate, worst) => {
                            out.pop();
                        }
                        _ => continue,
                    }
                }
                let pos = out.partition_point(|&x| less(x, candidate));
                out.insert(pos, candidate);
            }
            return;
        }
        let (l, r) = (2 * node + 1, 2 * node + 2);
        let bl = box_lower_bound(q, &self.nodes[l].lo, &self.nodes[l].hi);
        let br = box_lower_bound(q, &self.nodes[r].lo, &self.nodes[r].hi);
        let (first, bf, second, bs) = if bl <= br {
            (l, bl, r, br)
        } else {
            (r, br, l, bl)
        };
        // A box at exactly the worst distance may hold a tie with a smaller index: visit it.
        let worst = |out: &Vec<(f32, u32)>| {
            if out.len() < k {
                f32::INFINITY
            } else {
                out.last().map_or(f32::INFINITY, |w| w.0)
            }
        };
        if bf <= worst(out) {
            self.nearest_in(first, q, k, exclude, out);
        }
        if bs <= worst(out) {
            self.nearest_in(second, q, k, exclude, out);
        }
    }

    /// Every point with squared distance `<= radius2` from `q` (original index `exclude`
    /// skipped), sorted by `(squared distance, index)`, into `out` (cleared).
    pub fn within(
        &self,
        q: &[f32; 3],
        radius2: f32,
        exclude: Option<u32>,
        out: &mut Vec<(f32, u32)>,
    ) {
        out.clear();
        if self.points.is_empty() {
            return;
        }
        let mut stack = vec![0usize];
        while let Some(node) = stack.pop() {
            let nd = self.nodes[node];
            if box_lower_bound(q, &nd.lo, &nd.hi) > radius2 {
                continue;
            }
            if node >= self.first_leaf {
                let (s, e) = (nd.start as usize, nd.end as usize);
                for (p, &id) in self.points[s..e].iter().zip(&self.ids[s..e]) {
                    let d = squared_distance(p, q);
                    if d <= radius2 && Some(id) != exclude {
                        out.push((d, id));
                    }
                }
            } else {
                stack.push(2 * node + 2);
                stack.push(2 * node + 1);
            }
        }
        out.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    }
}

/// `(d, i) < (d', i')` lexicographically.
#[inline]
fn less(a: (f32, u32), b: (f32, u32)) -> bool {
    a.0 < b.0 || (a.0 == b.0 && a.1 < b.1)
}

/// Reorders `items` so that each of the `2^depth` count-halves (recursively) is a kd cell:
/// split at the median of the axis of largest extent, by `(coordinate, index)`.
fn partition(items: &mut [([f32; 3], u32)], depth: usize) {
    if depth == 0 || items.len() < 2 {
        return;
    }
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for (p, _) in items.iter() {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    let mut axis = 0;
    for a in 1..3 {
        if hi[a] - lo[a] > hi[axis] - lo[axis] {
            axis = a;
        }
    }
    let mid = items.len() / 2;
    items.select_nth_unstable_by(mid, |x, y| {
        x.0[axis].total_cmp(&y.0[axis]).then(x.1.cmp(&y.1))
    });
    let (left, right) = items.split_at_mut(mid);
    if left.len() + right.len() >= PARALLEL_PARTITION {
        rayon::join(
            || partition(left, depth - 1),
            || partition(right, depth - 1),
        );
    } else {
        partition(left, depth - 1);
        partition(right, depth - 1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn leaves_partition_all_points_and_boxes_contain_them() {
        let pts: Vec<[f32; 3]> = (0..1000)
            .map(|i| {
                let t = i as f32 * 0.37;
                [t.sin(), (t * 1.3).cos(), (i % 7) as f32]
            })
            .collect();
        let tree = KdTree::new(&pts, 8);
        let mut ids = tree.ids.clone();
        ids.sort_unstable();
        assert_eq!(ids, (0..1000).collect::<Vec<u32>>());
        for node in &tree.nodes {
            for p in &tree.points[node.start as usize..node.end as usize] {
                for ((lo, hi), x) in node.lo.iter().zip(&node.hi).zip(p) {
                    assert!(lo <= x && x <= hi);
                }
            }
        }
        for leaf in &tree.nodes[tree.first_leaf..] {
            assert!((4..=8).contains(&(leaf.end - leaf.start)));
        }
    }

    #[test]
    fn all_identical_points_still_balance() {
        let pts = vec![[1.0f32, 2.0, 3.0]; 300];
        let tree = KdTree::new(&pts, 16);
        let mut out = Vec::new();
        tree.nearest(&[1.0, 2.0, 3.0], 5, Some(2), &mut out);
        assert_eq!(out, vec![(0.0, 0), (0.0, 1), (0.0, 3), (0.0, 4), (0.0, 5)]);
    }
}
