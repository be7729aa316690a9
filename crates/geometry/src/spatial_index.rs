//! The one spatial index of the workspace: a static, count-balanced 3-d kd-tree answering
//! k-nearest-neighbour and radius queries over a fixed point set. Every neighbourhood of the
//! thesis goes through it: the curvature neighbourhoods `N_i` of eq. 5.1-5.3 (metric and
//! loss alike), the projector's k-NN graph (eq. 5.4, k = 7), AttRef's neighbourhoods (eq. 5.5,
//! k = 15), the Chamfer correspondences (eq. 5.6-5.7), the barycentre graph of TriConv
//! (ch. 6.3, k = 20), and the pruning of fast farthest point sampling.
//!
//! # Why its own tree
//! A kd-tree that splits by coordinate *value* (kiddo's, most textbook ones) cannot split a
//! bucket of identical points: the bucket overflows its leaf or the build recurses without
//! progress, and every query that reaches it scans all of it, so `n` copies of one point cost
//! `O(n²)`. This tree splits by *count*: the median of `(coordinate, index)`, a total order, so
//! identical points are split by index like any others and every input, duplicates and
//! collinear runs included, gives a balanced tree of depth `⌈log₂(n / leaf)⌉`. Measured
//! against kiddo on 1M points in `docs/geometry.md`.
//!
//! # Conventions
//! - Results are ordered by `(squared distance, index)`: ties go to the smaller index, so every
//!   answer is deterministic and independent of the thread count.
//! - Squared distances are `dx·dx + dy·dy + dz·dz` in `f32`, left to right
//!   ([`squared_distance`]), the one expression every caller compares against.
//! - Self-queries exclude the query point by *index*: coincident duplicates are neighbours at
//!   distance 0.
//!
//! # Cost on degenerate inputs
//! Every node stores the smallest original index it holds. A subtree is visited only when its
//! box bound and smallest index, `(bound, min index)`, precede the current `k`-th result in the
//! `(distance, index)` order. On `n` identical points the first `k` indices are found in the
//! leftmost leaf and every other subtree is cut at once, so a query costs `O(log n + k)` there
//! too, not `O(n)`: building is `O(n log n)` and a batch of `n` queries `O(n (log n + k))` on
//! any input. Radius queries are output-sensitive (all points within the radius are returned).
//!
//! # Exactness
//! The box lower bound uses the same expression on per-axis gaps; float subtraction and
//! multiplication are monotonic, so the bound never exceeds the computed distance of any point
//! in the box and pruning is exact, never approximate.
//!
//! # Layout
//! Heap order: node `i` has children `2i+1`, `2i+2`; all leaves are at the same depth and hold
//! between `leaf_size/2` and `leaf_size` points (fewer only when the cloud is smaller). Points
//! are stored reordered, leaf by leaf ("slots"), with their original indices; tree walkers such
//! as fast farthest point sampling read this layout through [`SpatialIndex::nodes`],
//! [`SpatialIndex::slot_points`] and [`SpatialIndex::slot_ids`].

use rayon::prelude::*;

use crate::error::{Error, Result};

mod batch_queries;
use crate::tri_mesh::check_finite;

/// Leaf size for k-NN and radius queries (a common choice for k ≈ 7-20; not tuned).
pub const DEFAULT_LEAF_SIZE: usize = 16;

/// Subtrees smaller than this are partitioned on the current thread.
const PARALLEL_PARTITION: usize = 1 << 14;

/// `|a − b|²` in `f32`, in the one evaluation order of the index (module docs).
///
/// ```
/// assert_eq!(meshgnn_geometry::squared_distance(&[1.0, 2.0, 3.0], &[1.0, 0.0, 0.0]), 13.0);
/// ```
#[inline]
pub fn squared_distance(a: &[f32; 3], b: &[f32; 3]) -> f32 {
    let dx = a[0] - b[0];
    let dy = a[1] - b[1];
    let dz = a[2] - b[2];
    dx * dx + dy * dy + dz * dz
}

/// The squared distance from `q` to the box `[lo, hi]`: a lower bound of [`squared_distance`]
/// to any point inside it (exact pruning, module docs).
///
/// ```
/// use meshgnn_geometry::box_squared_distance;
/// assert_eq!(box_squared_distance(&[3.0, 0.5, 0.0], &[0.0; 3], &[1.0; 3]), 4.0);
/// assert_eq!(box_squared_distance(&[0.5, 0.5, 0.5], &[0.0; 3], &[1.0; 3]), 0.0);
/// ```
#[inline]
pub fn box_squared_distance(q: &[f32; 3], lo: &[f32; 3], hi: &[f32; 3]) -> f32 {
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

/// One node of the tree: its bounding box, its range of slots and the smallest original index
/// among its points.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpatialNode {
    /// Lower corner of the bounding box of the node's points.
    pub lo: [f32; 3],
    /// Upper corner of the bounding box.
    pub hi: [f32; 3],
    /// First slot of the node.
    pub start: u32,
    /// One past its last slot.
    pub end: u32,
    /// Smallest original point index in the node (`u32::MAX` when empty).
    pub min_id: u32,
}

/// The result of a batch k-NN query: `k` neighbours per query point.
///
/// # Conventions
/// `indices` is `#Q×k` row-major `u32`; row `i` lists the neighbours of query `i` nearest
/// first, ties by index; `squared_distances` is aligned with it ([`squared_distance`]).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Neighbours {
    /// Neighbours per row.
    pub k: usize,
    /// `#Q×k` neighbour indices, nearest first, ties by index.
    pub indices: Vec<u32>,
    /// `#Q×k` squared distances aligned with `indices`.
    pub squared_distances: Vec<f32>,
}

impl Neighbours {
    /// Number of query points (rows).
    ///
    /// ```
    /// let nn = meshgnn_geometry::Neighbours { k: 2, indices: vec![1, 2, 0, 2], squared_distances: vec![0.0; 4] };
    /// assert_eq!(nn.len(), 2);
    /// ```
    pub fn len(&self) -> usize {
        self.indices.len().checked_div(self.k).unwrap_or(0)
    }

    /// True when there are no rows.
    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }

    /// The neighbour indices of row `i` (empty when out of range).
    ///
    /// ```
    /// let nn = meshgnn_geometry::Neighbours { k: 2, indices: vec![1, 2, 0, 2], squared_distances: vec![0.0; 4] };
    /// assert_eq!(nn.row(1), &[0, 2]);
    /// assert!(nn.row(2).is_empty());
    /// ```
    pub fn row(&self, i: usize) -> &[u32] {
        self.indices
            .get(i * self.k..(i + 1) * self.k)
            .unwrap_or(&[])
    }
}

/// A kd-tree over `points: #P×3`, built once in O(P log P) (parallel) and queried many times.
/// See the module docs for the conventions and the cost on duplicate points. The default is
/// the empty index.
#[derive(Debug, Clone, Default)]
pub struct SpatialIndex {
    /// Points reordered leaf by leaf, `#P`.
    points: Vec<[f32; 3]>,
    /// Original index of each slot, `#P`.
    ids: Vec<u32>,
    /// Nodes in heap order.
    nodes: Vec<SpatialNode>,
    /// Index of the first leaf in `nodes` (leaves are `first_leaf..nodes.len()`).
    first_leaf: usize,
}

impl SpatialIndex {
    /// Builds the index over `points: #P×3` with [`DEFAULT_LEAF_SIZE`]. An empty set is
    /// allowed (every query then finds nothing). Errors when a coordinate is NaN/infinite or
    /// `#P` does not fit `u32` indices.
    ///
    /// ```
    /// use meshgnn_geometry::SpatialIndex;
    /// let index = SpatialIndex::new(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])?;
    /// assert_eq!(index.len(), 2);
    /// assert!(SpatialIndex::new(&[[f32::NAN, 0.0, 0.0]]).is_err());
    /// # Ok::<(), meshgnn_geometry::Error>(())
    /// ```
    pub fn new(points: &[[f32; 3]]) -> Result<Self> {
        Self::with_leaf_size(points, DEFAULT_LEAF_SIZE)
    }

    /// [`SpatialIndex::new`] with `leaf_size` points per leaf at most (at least 1). Results do
    /// not depend on it, only speed: larger leaves suit walkers that rescan whole leaves.
    ///
    /// ```
    /// use meshgnn_geometry::SpatialIndex;
    /// let pts: Vec<[f32; 3]> = (0..100).map(|i| [i as f32, 0.0, 0.0]).collect();
    /// let index = SpatialIndex::with_leaf_size(&pts, 8)?;
    /// assert!(index.nodes()[index.first_leaf()..].iter().all(|n| n.end - n.start <= 8));
    /// # Ok::<(), meshgnn_geometry::Error>(())
    /// ```
    pub fn with_leaf_size(points: &[[f32; 3]], leaf_size: usize) -> Result<Self> {
        if u32::try_from(points.len()).is_err() {
            return Err(Error::InvalidParameter {
                name: "points",
                message: format!("{} points exceed the 2^32 supported", points.len()),
            });
        }
        check_finite("point", points)?;
        Ok(Self::build(points, leaf_size.max(1)))
    }

    fn build(points: &[[f32; 3]], leaf_size: usize) -> Self {
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
            SpatialNode {
                lo: [f32::INFINITY; 3],
                hi: [f32::NEG_INFINITY; 3],
                start: 0,
                end: 0,
                min_id: u32::MAX,
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
        // Boxes and smallest indices bottom-up: leaves in parallel, then unions.
        nodes[first_leaf..].par_iter_mut().for_each(|node| {
            let range = node.start as usize..node.end as usize;
            for p in &points[range.clone()] {
                for ((lo, hi), &x) in node.lo.iter_mut().zip(node.hi.iter_mut()).zip(p) {
                    *lo = lo.min(x);
                    *hi = hi.max(x);
                }
            }
            node.min_id = ids[range].iter().copied().min().unwrap_or(u32::MAX);
        });
        for i in (0..first_leaf).rev() {
            let (l, r) = (nodes[2 * i + 1], nodes[2 * i + 2]);
            for a in 0..3 {
                nodes[i].lo[a] = l.lo[a].min(r.lo[a]);
                nodes[i].hi[a] = l.hi[a].max(r.hi[a]);
            }
            nodes[i].min_id = l.min_id.min(r.min_id);
        }
        Self {
            points,
            ids,
            nodes,
            first_leaf,
        }
    }

    /// The same tree over its points renumbered in slot order, and the permutation: the new
    /// index's point `i` is `slot_points()[i]`, the original point `order[i]`. It has the
    /// nodes of [`SpatialIndex::with_leaf_size`] on the slot-ordered points (every node holds
    /// a range of slots, and the `(coordinate, index)` medians split the renumbered points the
    /// same way), so it answers every query as that build would, without a second build: a
    /// cloud then processed in this spatially coherent order keeps its queries and gathers in
    /// cache.
    ///
    /// ```
    /// use meshgnn_geometry::SpatialIndex;
    /// let pts: Vec<[f32; 3]> = (0..100).map(|i| [((i * 37) % 100) as f32, 0.0, 0.0]).collect();
    /// let (index, order) = SpatialIndex::new(&pts)?.into_slot_order();
    /// assert_eq!(index.slot_ids(), (0..100).collect::<Vec<u32>>());
    /// assert!(order.iter().enumerate().all(|(i, &o)| index.slot_points()[i] == pts[o as usize]));
    /// # Ok::<(), meshgnn_geometry::Error>(())
    /// ```
    pub fn into_slot_order(self) -> (Self, Vec<u32>) {
        let Self {
            points,
            ids,
            mut nodes,
            first_leaf,
        } = self;
        for node in &mut nodes {
            node.min_id = if node.start < node.end {
                node.start
            } else {
                u32::MAX
            };
        }
        let renumbered = (0..points.len() as u32).collect();
        (
            Self {
                points,
                ids: renumbered,
                nodes,
                first_leaf,
            },
            ids,
        )
    }

    /// Number of indexed points #P.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True when no point is indexed.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The nodes in heap order (children of `i` at `2i+1`, `2i+2`; module docs, Layout).
    pub fn nodes(&self) -> &[SpatialNode] {
        &self.nodes
    }

    /// Position of the first leaf in [`SpatialIndex::nodes`]; the leaves follow it.
    pub fn first_leaf(&self) -> usize {
        self.first_leaf
    }

    /// The points in slot order (leaf by leaf), `#P×3`.
    pub fn slot_points(&self) -> &[[f32; 3]] {
        &self.points
    }

    /// The original index of each slot, `#P`.
    pub fn slot_ids(&self) -> &[u32] {
        &self.ids
    }

    /// The `k` nearest points to `q`, ordered by `(squared distance, index)`, skipping original
    /// index `exclude`; fewer when the index holds fewer. Results go to `out` (cleared) as
    /// `(squared distance, index)`.
    ///
    /// ```
    /// use meshgnn_geometry::SpatialIndex;
    /// let index = SpatialIndex::new(&[[0.0; 3], [2.0, 0.0, 0.0], [0.0; 3], [1.0, 0.0, 0.0]])?;
    /// let mut out = Vec::new();
    /// index.nearest(&[0.0; 3], 3, Some(0), &mut out);
    /// assert_eq!(out, vec![(0.0, 2), (1.0, 3), (4.0, 1)]);
    /// # Ok::<(), meshgnn_geometry::Error>(())
    /// ```
    pub fn nearest(&self, q: &[f32; 3], k: usize, exclude: Option<u32>, out: &mut Vec<(f32, u32)>) {
        self.nearest_within(q, k, f32::INFINITY, exclude, out);
    }

    /// [`SpatialIndex::nearest`] restricted to squared distances `<= radius2`: the capped ball
    /// query (PointNet++), equal to the first `k` of [`SpatialIndex::within`] at the cost of a
    /// k-NN query, however many points lie in the ball.
    ///
    /// ```
    /// use meshgnn_geometry::SpatialIndex;
    /// let index = SpatialIndex::new(&[[0.0; 3], [1.0, 0.0, 0.0], [3.0, 0.0, 0.0]])?;
    /// let mut out = Vec::new();
    /// index.nearest_within(&[0.0; 3], 5, 1.0, None, &mut out);
    /// assert_eq!(out, vec![(0.0, 0), (1.0, 1)]);
    /// # Ok::<(), meshgnn_geometry::Error>(())
    /// ```
    pub fn nearest_within(
        &self,
        q: &[f32; 3],
        k: usize,
        radius2: f32,
        exclude: Option<u32>,
        out: &mut Vec<(f32, u32)>,
    ) {
        out.clear();
        if k == 0 || self.points.is_empty() {
            return;
        }
        let query = Query {
            q,
            k,
            radius2,
            exclude,
        };
        self.nearest_in(0, &query, out);
    }

    /// The search below `node`; returns the number of leaves it scanned (the cost measure
    /// of the degenerate-input tests).
    fn nearest_in(&self, node: usize, query: &Query<'_>, out: &mut Vec<(f32, u32)>) -> usize {
        if node >= self.first_leaf {
            self.scan_leaf(node, query, out);
            return 1;
        }
        let (l, r) = (2 * node + 1, 2 * node + 2);
        let key = |c: usize| {
            let nd = &self.nodes[c];
            (box_squared_distance(query.q, &nd.lo, &nd.hi), nd.min_id)
        };
        let (kl, kr) = (key(l), key(r));
        let (first, kf, second, ks) = if less(kl, kr) {
            (l, kl, r, kr)
        } else {
            (r, kr, l, kl)
        };
        // A subtree can improve the result only if its best conceivable `(bound, min index)`
        // precedes the current worst: ties at the worst distance need a smaller index.
        let mut leaves = 0;
        if less(kf, query.worst(out)) {
            leaves += self.nearest_in(first, query, out);
        }
        if less(ks, query.worst(out)) {
            leaves += self.nearest_in(second, query, out);
        }
        leaves
    }

    /// Offers every point of leaf `leaf` to `out`, the sorted `k` best so far.
    #[inline]
    fn scan_leaf(&self, leaf: usize, query: &Query<'_>, out: &mut Vec<(f32, u32)>) {
        let nd = self.nodes[leaf];
        let (s, e) = (nd.start as usize, nd.end as usize);
        let mut worst = query.worst(out);
        for (p, &id) in self.points[s..e].iter().zip(&self.ids[s..e]) {
            let candidate = (squared_distance(p, query.q), id);
            // the common case first: farther than the current worst
            if candidate.0 > worst.0 || !less(candidate, worst) || Some(id) == query.exclude {
                continue;
            }
            insert_sorted(out, query.k, candidate);
            worst = query.worst(out);
        }
    }

    /// Every point with squared distance `<= radius2` from `q` (original index `exclude`
    /// skipped), sorted by `(squared distance, index)`, into `out` (cleared).
    ///
    /// ```
    /// use meshgnn_geometry::SpatialIndex;
    /// let index = SpatialIndex::new(&[[0.0; 3], [1.0, 0.0, 0.0], [3.0, 0.0, 0.0]])?;
    /// let mut out = Vec::new();
    /// index.within(&[1.0, 0.0, 0.0], 4.0, Some(1), &mut out);
    /// assert_eq!(out, vec![(1.0, 0), (4.0, 2)]);
    /// # Ok::<(), meshgnn_geometry::Error>(())
    /// ```
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
            if box_squared_distance(q, &nd.lo, &nd.hi) > radius2 {
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

    /// The points within squared distance `radius2` of `q`, thinned evenly to at most `max`:
    /// when the ball holds `n > max` points, every `⌈n / max⌉`-th of them in slot order (the
    /// tree's spatial order), so the kept points still span the whole ball. Results go to
    /// `out` (cleared) as `(squared distance, index)` in slot order. Subtrees whose box lies
    /// inside the ball are counted and strided without being scanned, so a query costs
    /// `O(log n + boundary leaves + max)` however many points the ball holds: a fixed-radius
    /// neighbourhood with a bounded cost (the fixed-scale curvature of `curvature_at_scale`).
    ///
    /// ```
    /// use meshgnn_geometry::SpatialIndex;
    /// let line: Vec<[f32; 3]> = (0..100).map(|i| [i as f32, 0.0, 0.0]).collect();
    /// let index = SpatialIndex::new(&line)?;
    /// let mut out = Vec::new();
    /// index.within_thinned(&[50.0, 0.0, 0.0], 100.0, 7, &mut out); // 21 points in the ball
    /// assert_eq!(out.len(), 7);
    /// let mut xs: Vec<f32> = out.iter().map(|&(_, i)| line[i as usize][0]).collect();
    /// xs.sort_by(f32::total_cmp);
    /// assert_eq!(xs, [40.0, 43.0, 46.0, 49.0, 52.0, 55.0, 58.0]); // every third
    /// # Ok::<(), meshgnn_geometry::Error>(())
    /// ```
    pub fn within_thinned(
        &self,
        q: &[f32; 3],
        radius2: f32,
        max: usize,
        out: &mut Vec<(f32, u32)>,
    ) {
        out.clear();
        if self.points.is_empty() || max == 0 {
            return;
        }
        let mut count = 0usize;
        self.visit_ball(0, q, radius2, &mut |slots| count += slots.len());
        let stride = count.div_ceil(max).max(1);
        let mut seen = 0usize;
        self.visit_ball(0, q, radius2, &mut |slots| {
            // the first slot of this run whose running position is a multiple of `stride`
            let skip = (stride - seen % stride) % stride;
            for slot in slots.clone().skip(skip).step_by(stride) {
                out.push((squared_distance(&self.points[slot], q), self.ids[slot]));
            }
            seen += slots.len();
        });
    }

    /// Calls `visit` with runs of consecutive slots, in slot order, that together are exactly
    /// the points of `node`'s subtree within `radius2` of `q`.
    fn visit_ball(
        &self,
        node: usize,
        q: &[f32; 3],
        radius2: f32,
        visit: &mut impl FnMut(std::ops::Range<usize>),
    ) {
        let nd = self.nodes[node];
        if box_squared_distance(q, &nd.lo, &nd.hi) > radius2 || nd.start == nd.end {
            return;
        }
        let (s, e) = (nd.start as usize, nd.end as usize);
        // The farthest corner: every point of the box is at most this far (monotonic ops).
        let far = |a: usize| (q[a] - nd.lo[a]).abs().max((nd.hi[a] - q[a]).abs());
        let (fx, fy, fz) = (far(0), far(1), far(2));
        if fx * fx + fy * fy + fz * fz <= radius2 {
            visit(s..e);
        } else if node >= self.first_leaf {
            for slot in s..e {
                if squared_distance(&self.points[slot], q) <= radius2 {
                    visit(slot..slot + 1);
                }
            }
        } else {
            self.visit_ball(2 * node + 1, q, radius2, visit);
            self.visit_ball(2 * node + 2, q, radius2, visit);
        }
    }
}

/// One k-NN query: the point, how many, the inclusive squared radius, the excluded index.
struct Query<'a> {
    q: &'a [f32; 3],
    k: usize,
    radius2: f32,
    exclude: Option<u32>,
}

impl Query<'_> {
    /// The `(distance, index)` a new result must precede: the `k`-th found so far, or the
    /// radius (inclusive: any index precedes `u32::MAX`, never a point index) while fewer.
    #[inline]
    fn worst(&self, out: &[(f32, u32)]) -> (f32, u32) {
        if out.len() < self.k {
            (self.radius2, u32::MAX)
        } else {
            out.last().copied().unwrap_or((self.radius2, u32::MAX))
        }
    }
}

/// Inserts `candidate` into `out` (sorted, at most `k`), dropping the worst when full.
#[inline]
fn insert_sorted(out: &mut Vec<(f32, u32)>, k: usize, candidate: (f32, u32)) {
    if out.len() == k {
        out.pop();
    }
    // from the back: `out` is short and sorted
    out.push(candidate);
    let mut i = out.len() - 1;
    while i > 0 && less(candidate, out[i - 1]) {
        out[i] = out[i - 1];
        i -= 1;
    }
    out[i] = candidate;
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
    use rand::{Rng, SeedableRng, rngs::StdRng};

    /// `k` nearest by sorting every distance, ties by index.
    fn brute(points: &[[f32; 3]], q: &[f32; 3], k: usize, exclude: Option<u32>) -> Vec<(f32, u32)> {
        let mut all: Vec<(f32, u32)> = points
            .iter()
            .enumerate()
            .filter(|&(j, _)| Some(j as u32) != exclude)
            .map(|(j, p)| (squared_distance(p, q), j as u32))
            .collect();
        all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        all.truncate(k);
        all
    }

    #[test]
    fn slot_order_tree_is_the_tree_built_on_the_slot_order() {
        // duplicates and ties on the split coordinates included
        for (n, leaf) in [(5000, 16), (3001, 1), (777, 100), (3, 16), (0, 16)] {
            let points = cloud_with_ties(9, n);
            let index = SpatialIndex::with_leaf_size(&points, leaf).unwrap();
            let ids = index.slot_ids().to_vec();
            let (renumbered, order) = index.into_slot_order();
            assert_eq!(order, ids);
            let rebuilt = SpatialIndex::with_leaf_size(renumbered.slot_points(), leaf).unwrap();
            assert_eq!(
                renumbered.nodes(),
                rebuilt.nodes(),
                "{n} points, leaf {leaf}"
            );
            assert_eq!(renumbered.first_leaf(), rebuilt.first_leaf());
            // each leaf holds the same points (its order within a leaf is the build's)
            for node in &renumbered.nodes()[renumbered.first_leaf()..] {
                let slots = node.start as usize..node.end as usize;
                let mut a = renumbered.slot_ids()[slots.clone()].to_vec();
                let mut b = rebuilt.slot_ids()[slots].to_vec();
                a.sort_unstable();
                b.sort_unstable();
                assert_eq!(a, b);
            }
            for (i, &id) in renumbered.slot_ids().iter().enumerate() {
                assert_eq!(
                    renumbered.slot_points()[i],
                    points[order[id as usize] as usize]
                );
            }
            if n > 0 {
                let queries = &renumbered.slot_points()[..n.min(50)];
                let k = 7.min(n);
                assert_eq!(
                    renumbered.knn(queries, k).unwrap(),
                    rebuilt.knn(queries, k).unwrap()
                );
            }
        }
    }

    #[test]
    fn thinned_ball_is_the_ball_or_an_even_subset_of_it() {
        let points = cloud_with_ties(5, 5000);
        let index = SpatialIndex::new(&points).unwrap();
        let mut rng = StdRng::seed_from_u64(6);
        let (mut all, mut thin) = (Vec::new(), Vec::new());
        for _ in 0..200 {
            let q: [f32; 3] = std::array::from_fn(|_| rng.random_range(-0.2f32..1.2));
            let r2 = rng.random_range(0.0f32..0.2);
            let max = rng.random_range(1usize..300);
            index.within(&q, r2, None, &mut all);
            index.within_thinned(&q, r2, max, &mut thin);
            thin.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            if all.len() <= max {
                assert_eq!(thin, all);
            } else {
                // ⌈n / stride⌉ points with stride ⌈n / max⌉: at most max, more than max / 2
                assert!(
                    thin.len() <= max && 2 * thin.len() > max,
                    "{} of {max}",
                    thin.len()
                );
                assert!(thin.iter().all(|t| {
                    all.binary_search_by(|a| a.0.total_cmp(&t.0).then(a.1.cmp(&t.1)))
                        .is_ok()
                }));
            }
        }
    }

    /// Uniform points, a quarter of them copies of earlier ones, a third on a coarse grid.
    fn cloud_with_ties(seed: u64, n: usize) -> Vec<[f32; 3]> {
        let mut rng = StdRng::seed_from_u64(seed);
        let mut pts: Vec<[f32; 3]> = (0..n)
            .map(|_| [rng.random(), rng.random(), rng.random()])
            .collect();
        for i in (3..n).step_by(4) {
            pts[i] = pts[rng.random_range(0..i)];
        }
        for (i, p) in pts.iter_mut().enumerate().take(n / 3) {
            *p = [(i % 5) as f32, ((i / 5) % 5) as f32, 0.0];
        }
        pts
    }

    /// Leaves visited by one `nearest` query.
    fn leaves_visited(index: &SpatialIndex, q: &[f32; 3], k: usize, exclude: Option<u32>) -> usize {
        let query = Query {
            q,
            k,
            radius2: f32::INFINITY,
            exclude,
        };
        index.nearest_in(0, &query, &mut Vec::new())
    }

    #[test]
    fn leaves_partition_all_points_and_boxes_contain_them() {
        let pts: Vec<[f32; 3]> = (0..1000)
            .map(|i| {
                let t = i as f32 * 0.37;
                [t.sin(), (t * 1.3).cos(), (i % 7) as f32]
            })
            .collect();
        let index = SpatialIndex::with_leaf_size(&pts, 8).unwrap();
        let mut ids = index.ids.clone();
        ids.sort_unstable();
        assert_eq!(ids, (0..1000).collect::<Vec<u32>>());
        for node in &index.nodes {
            let range = node.start as usize..node.end as usize;
            for p in &index.points[range.clone()] {
                for ((lo, hi), x) in node.lo.iter().zip(&node.hi).zip(p) {
                    assert!(lo <= x && x <= hi);
                }
            }
            assert_eq!(node.min_id, index.ids[range].iter().copied().min().unwrap());
        }
        for leaf in &index.nodes[index.first_leaf..] {
            assert!((4..=8).contains(&(leaf.end - leaf.start)));
        }
    }

    #[test]
    fn nearest_and_within_match_brute_force_with_duplicates_and_ties() {
        let pts = cloud_with_ties(2, 900);
        let index = SpatialIndex::new(&pts).unwrap();
        let queries = cloud_with_ties(3, 120);
        let mut out = Vec::new();
        for (i, q) in queries.iter().enumerate() {
            for (k, exclude) in [(1, None), (7, Some(i as u32)), (15, Some(0)), (40, None)] {
                index.nearest(q, k, exclude, &mut out);
                assert_eq!(out, brute(&pts, q, k, exclude), "query {i} k {k}");
            }
            for radius2 in [0.0f32, 0.0625, 1.0] {
                let all = brute(&pts, q, usize::MAX, Some(3));
                let want: Vec<(f32, u32)> =
                    all.into_iter().filter(|&(d, _)| d <= radius2).collect();
                index.within(q, radius2, Some(3), &mut out);
                assert_eq!(out, want, "query {i} radius² {radius2}");
                index.nearest_within(q, 5, radius2, Some(3), &mut out);
                assert_eq!(out, want[..want.len().min(5)], "capped, query {i}");
            }
        }
    }

    #[test]
    fn batch_queries_equal_single_queries() {
        let pts = cloud_with_ties(4, 700);
        let index = SpatialIndex::new(&pts).unwrap();
        let g = index.knn_graph(7).unwrap();
        let q = index.knn(&pts[..50], 15).unwrap();
        for (i, p) in pts.iter().enumerate() {
            let want = brute(&pts, p, 7, Some(i as u32));
            assert_eq!(g.row(i), want.iter().map(|x| x.1).collect::<Vec<_>>());
            assert_eq!(
                &g.squared_distances[i * 7..(i + 1) * 7],
                want.iter().map(|x| x.0).collect::<Vec<_>>()
            );
        }
        for (i, p) in pts[..50].iter().enumerate() {
            let want: Vec<u32> = brute(&pts, p, 15, None).iter().map(|x| x.1).collect();
            assert_eq!(q.row(i), want.as_slice());
        }
        assert!(index.knn_graph(700).is_err());
        assert!(index.knn_graph(0).is_err());
        assert!(index.knn(&pts, 701).is_err());
        assert!(matches!(
            index.knn(&[[0.0, f32::INFINITY, 0.0]], 1),
            Err(Error::NonFinite { index: 0, .. })
        ));
    }

    #[test]
    fn graphs_wider_than_a_leaf_equal_brute_force() {
        // k of a leaf's 8-16 points and more (the face classifier's k = 20): a leaf of at
        // most k points has no bound of its own and its rows take one walk per point; on
        // clustered and duplicated points
        let mut rng = StdRng::seed_from_u64(4);
        let mut pts = cloud_with_ties(6, 1500);
        for i in 0..1500 {
            let c = [(i % 5) as f32, -2.0, 0.5];
            pts.push(match i % 3 {
                0 => c,
                _ => std::array::from_fn(|a| c[a] + rng.random_range(-0.02f32..0.02)),
            });
        }
        let index = SpatialIndex::new(&pts).unwrap();
        for k in [16, 20, 33, 64] {
            let g = index.knn_graph(k).unwrap();
            for (i, p) in pts.iter().enumerate().step_by(11) {
                let want = brute(&pts, p, k, Some(i as u32));
                assert_eq!(
                    g.row(i),
                    want.iter().map(|x| x.1).collect::<Vec<_>>(),
                    "k {k} point {i}"
                );
                assert_eq!(
                    &g.squared_distances[i * k..(i + 1) * k],
                    want.iter().map(|x| x.0).collect::<Vec<_>>()
                );
            }
        }
    }

    #[test]
    fn graph_rows_of_a_subset_equal_the_whole_graph_and_brute_force() {
        // clustered, duplicated and spread points: leaves take the batched route, the dense
        // duplicate clusters the per-point fallback
        let mut rng = StdRng::seed_from_u64(9);
        let mut pts = cloud_with_ties(5, 3000);
        for i in 0..2000 {
            let c = [(i % 3) as f32 * 4.0, 1.0, 0.0];
            pts.push(match i % 4 {
                0 => c,
                _ => std::array::from_fn(|a| c[a] + rng.random_range(-0.01f32..0.01)),
            });
        }
        let index = SpatialIndex::new(&pts).unwrap();
        let all = index.knn_graph(7).unwrap();
        for (i, p) in pts.iter().enumerate().step_by(7) {
            let want = brute(&pts, p, 7, Some(i as u32));
            assert_eq!(
                all.row(i),
                want.iter().map(|x| x.1).collect::<Vec<_>>(),
                "{i}"
            );
        }
        let ids: Vec<u32> = (0..pts.len() as u32).rev().filter(|i| i % 3 != 1).collect();
        let some = index.knn_rows(&ids, 7).unwrap();
        for (r, &i) in ids.iter().enumerate() {
            assert_eq!(some.row(r), all.row(i as usize));
            assert_eq!(
                &some.squared_distances[r * 7..(r + 1) * 7],
                &all.squared_distances[i as usize * 7..(i as usize + 1) * 7]
            );
        }
        // 2000 copies of one point: more than 64 candidate leaves, the per-point route
        let same = SpatialIndex::new(&[[1.0f32, 2.0, 3.0]; 2000]).unwrap();
        let rows = same.knn_rows(&[1999, 2], 4).unwrap();
        assert_eq!(rows.indices, vec![0, 1, 2, 3, 0, 1, 3, 4]);
        assert!(index.knn_rows(&[], 7).unwrap().is_empty());
        assert!(index.knn_rows(&[3, 3], 7).is_err());
        assert!(index.knn_rows(&[pts.len() as u32], 7).is_err());
        assert!(index.knn_rows(&[0], 0).is_err());
    }

    #[test]
    fn bounded_nearest_of_many_equals_one_query_at_a_time() {
        let pts = cloud_with_ties(6, 2000);
        let index = SpatialIndex::new(&pts).unwrap();
        let mut rng = StdRng::seed_from_u64(4);
        // spatially ordered queries (most of them) and scattered ones, inside and outside
        let mut queries: Vec<[f32; 3]> = index.slot_points().iter().step_by(3).copied().collect();
        queries.extend(cloud_with_ties(8, 300).iter().map(|q| q.map(|x| x * 3.0)));
        let radii: Vec<f32> = queries
            .iter()
            .map(|_| rng.random_range(0.0f32..0.05))
            .collect();
        let got = index.nearest_within_each(&queries, &radii).unwrap();
        let mut out = Vec::new();
        for ((q, &r), g) in queries.iter().zip(&radii).zip(&got) {
            index.nearest_within(q, 1, r, None, &mut out);
            assert_eq!(*g, out.first().map(|x| x.1));
        }
        assert!(got.iter().any(Option::is_none) && got.iter().any(Option::is_some));
        assert!(index.nearest_within_each(&queries, &radii[1..]).is_err());
        assert!(index.nearest_within_each(&[[0.0; 3]], &[f32::NAN]).is_err());
        let empty = SpatialIndex::new(&[]).unwrap();
        assert_eq!(
            empty.nearest_within_each(&[[0.0; 3]], &[1.0]).unwrap(),
            vec![None]
        );
    }

    #[test]
    fn batch_queries_far_outside_the_index_box_are_answered() {
        let pts = cloud_with_ties(2, 500);
        let index = SpatialIndex::new(&pts).unwrap();
        let queries = [[1e6f32, -1e6, 3.0], [0.1, 0.2, 0.3], [-1e30, 0.0, 1e30]];
        let got = index.knn(&queries, 4).unwrap();
        for (i, q) in queries.iter().enumerate() {
            let want: Vec<u32> = brute(&pts, q, 4, None).iter().map(|x| x.1).collect();
            assert_eq!(got.row(i), want.as_slice());
        }
    }

    #[test]
    fn identical_points_take_neighbours_in_index_order_in_logarithmic_time() {
        let pts = vec![[1.0f32, 2.0, 3.0]; 300];
        let index = SpatialIndex::new(&pts).unwrap();
        let mut out = Vec::new();
        index.nearest(&[1.0, 2.0, 3.0], 5, Some(2), &mut out);
        assert_eq!(out, vec![(0.0, 0), (0.0, 1), (0.0, 3), (0.0, 4), (0.0, 5)]);
        let g = index.knn_graph(3).unwrap();
        assert_eq!(g.row(0), &[1, 2, 3]);
        assert_eq!(g.row(299), &[0, 1, 2]);
        // Leaves visited per query do not grow with the number of copies (a scan of the
        // bucket would visit all n / 16 of them).
        for n in [1_000usize, 64_000] {
            let pts = vec![[0.5f32, -1.0, 2.0]; n];
            let index = SpatialIndex::new(&pts).unwrap();
            for (k, exclude) in [(1, None), (7, Some(n as u32 - 1)), (15, Some(3))] {
                assert!(
                    leaves_visited(&index, &pts[0], k, exclude) <= 2,
                    "n {n} k {k}"
                );
            }
        }
    }

    #[test]
    fn collinear_and_equally_spaced_points_stay_logarithmic() {
        // Equal spacing: every point has two neighbours at each distance (ties everywhere).
        for n in [1_000usize, 64_000] {
            let pts: Vec<[f32; 3]> = (0..n).map(|i| [i as f32, 2.0 * i as f32, 0.0]).collect();
            let index = SpatialIndex::new(&pts).unwrap();
            for i in [0, n / 3, n - 1] {
                let q = &pts[i];
                let visited = leaves_visited(&index, q, 15, Some(i as u32));
                assert!(visited <= 4, "n {n} point {i}: {visited} leaves");
                let mut out = Vec::new();
                index.nearest(q, 15, Some(i as u32), &mut out);
                assert_eq!(out, brute(&pts, q, 15, Some(i as u32)));
            }
        }
    }

    #[test]
    fn empty_index_finds_nothing() {
        let index = SpatialIndex::new(&[]).unwrap();
        let mut out = vec![(1.0, 1)];
        index.nearest(&[0.0; 3], 3, None, &mut out);
        assert!(out.is_empty());
        index.within(&[0.0; 3], 1.0, None, &mut out);
        assert!(out.is_empty());
        assert!(index.knn(&[[0.0; 3]], 1).is_err());
    }
}
