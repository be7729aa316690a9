//! The batched queries of [`SpatialIndex`]: the k-NN graph (all rows, or the rows of chosen
//! points), many k-NN queries, many bounded nearest-point queries. Each reuses work between
//! neighbouring queries — one tree walk per leaf or per run of queries, candidate points
//! scanned with vectorised distances, queries in Morton order — and gives exactly the answers
//! of one [`SpatialIndex::nearest`] walk per query (same distances, same `(distance, index)`
//! order), so callers may mix them freely.

use rayon::prelude::*;

use super::{Neighbours, Query, SpatialIndex, SpatialNode, insert_sorted, less};
use crate::error::{Error, Result};
use crate::tri_mesh::check_finite;

/// Candidate leaves beyond which a leaf's k-NN rows fall back to one tree walk per point.
const LEAF_BATCH_CANDIDATES: usize = 64;

/// Consecutive queries of [`SpatialIndex::nearest_within_each`] that share one tree walk.
const QUERY_BLOCK: usize = 32;

/// The squared distance between the boxes of two nodes: a lower bound of
/// [`super::squared_distance`] between any point of one and any point of the other (per-axis gaps
/// never exceed the coordinate differences they bound, and the operations are monotonic).
#[inline]
fn box_box_squared_distance(a: &SpatialNode, b: &SpatialNode) -> f32 {
    let gap = |i: usize| {
        if b.lo[i] > a.hi[i] {
            b.lo[i] - a.hi[i]
        } else if a.lo[i] > b.hi[i] {
            a.lo[i] - b.hi[i]
        } else {
            0.0
        }
    };
    let (gx, gy, gz) = (gap(0), gap(1), gap(2));
    gx * gx + gy * gy + gz * gz
}

impl SpatialIndex {
    /// The k-NN graph rows of the points of leaf `leaf` whose slot is `wanted` (slot order),
    /// into `indices` and `squared_distances` (`#wanted×k` each): exactly what
    /// [`SpatialIndex::nearest`] finds, with one tree walk per leaf instead of one per point.
    /// Every query first takes its `k` best inside its own leaf; the worst of those over the
    /// leaf bounds which other leaves can hold a better neighbour (box-to-box distance and
    /// smallest index: the per-query pruning rule applied to the whole leaf at once), and each
    /// query then scans only those, still skipping the ones its own bound rules out. A leaf
    /// with at most `k` points, or with more than [`LEAF_BATCH_CANDIDATES`] candidate leaves
    /// (duplicates piled up), falls back to the per-point search, so the cost never exceeds it
    /// by more than that scan.
    fn leaf_knn_rows(
        &self,
        leaf: usize,
        wanted: &[bool],
        k: usize,
        indices: &mut [u32],
        squared_distances: &mut [f32],
        scratch: &mut LeafScratch,
    ) {
        let nd = self.nodes[leaf];
        let all = nd.start as usize..nd.end as usize;
        let LeafScratch {
            found,
            rows,
            candidates,
            others,
            distances,
        } = scratch;
        let query = |slot: usize| Query {
            q: &self.points[slot],
            k,
            radius2: f32::INFINITY,
            exclude: Some(self.ids[slot]),
        };
        let queries = || all.clone().filter(|&slot| wanted[slot]);
        rows.clear();
        let mut bound = (f32::NEG_INFINITY, 0u32);
        let mut batched = all.len() > k;
        if batched {
            for slot in queries() {
                let query = query(slot);
                found.clear();
                self.scan_leaf(leaf, &query, found);
                let worst = query.worst(found);
                if less(bound, worst) {
                    bound = worst;
                }
                rows.extend_from_slice(found);
            }
            candidates.clear();
            batched = self.collect_leaves(0, &nd, bound, candidates);
        }
        if batched {
            // the other candidate leaves' points, coordinates apart (the distance loop below
            // then runs in vector registers)
            others.clear();
            for &c in candidates.iter().filter(|&&c| c != leaf) {
                let cn = &self.nodes[c];
                let range = cn.start as usize..cn.end as usize;
                for (p, &id) in self.points[range.clone()].iter().zip(&self.ids[range]) {
                    others.push(p, id);
                }
            }
        }
        for (row, slot) in queries().enumerate() {
            let query = query(slot);
            found.clear();
            if batched {
                found.extend_from_slice(&rows[row * k..(row + 1) * k]);
                others.offer_all(&query, distances, found);
            } else {
                self.nearest_in(0, &query, found);
            }
            let span = row * k..(row + 1) * k;
            for ((i, d), &(fd, fi)) in indices[span.clone()]
                .iter_mut()
                .zip(&mut squared_distances[span])
                .zip(found.iter())
            {
                *i = fi;
                *d = fd;
            }
        }
    }

    /// Pushes onto `out` the leaves below `node` whose `(box-to-box distance to `from`,
    /// smallest index)` precedes `bound`; false (and `out` incomplete) once more than
    /// [`LEAF_BATCH_CANDIDATES`] qualify.
    fn collect_leaves(
        &self,
        node: usize,
        from: &SpatialNode,
        bound: (f32, u32),
        out: &mut Vec<usize>,
    ) -> bool {
        let nd = &self.nodes[node];
        let key = (box_box_squared_distance(from, nd), nd.min_id);
        if !less(key, bound) {
            return true;
        }
        if node >= self.first_leaf {
            out.push(node);
            return out.len() <= LEAF_BATCH_CANDIDATES;
        }
        self.collect_leaves(2 * node + 1, from, bound, out)
            && self.collect_leaves(2 * node + 2, from, bound, out)
    }

    /// The k-NN graph of the indexed points (thesis eq. 5.4, k = 7; eq. 5.1 neighbourhoods):
    /// for each point its `k` nearest *other* points, `#P×k`, in parallel. Errors when
    /// `k == 0` or `k >= #P`.
    ///
    /// ```
    /// use meshgnn_geometry::SpatialIndex;
    /// let index = SpatialIndex::new(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [3.0, 0.0, 0.0]])?;
    /// let nn = index.knn_graph(1)?;
    /// assert_eq!(nn.indices, vec![1, 0, 1]);
    /// assert_eq!(nn.squared_distances, vec![1.0, 1.0, 4.0]);
    /// # Ok::<(), meshgnn_geometry::Error>(())
    /// ```
    pub fn knn_graph(&self, k: usize) -> Result<Neighbours> {
        let all: Vec<u32> = (0..self.len() as u32).collect();
        self.knn_rows(&all, k)
    }

    /// The rows of [`SpatialIndex::knn_graph`] for the indexed points `ids` only (distinct
    /// original indices), `#ids×k`, row `i` for point `ids[i]`: what a model that reads the
    /// graph at some points needs, at a cost proportional to them. Errors when `k == 0`,
    /// `k >= #P`, or an id is out of range or repeated.
    ///
    /// ```
    /// use meshgnn_geometry::SpatialIndex;
    /// let index = SpatialIndex::new(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [3.0, 0.0, 0.0]])?;
    /// assert_eq!(index.knn_rows(&[2, 0], 1)?.indices, vec![1, 1]);
    /// assert!(index.knn_rows(&[0, 0], 1).is_err());
    /// # Ok::<(), meshgnn_geometry::Error>(())
    /// ```
    pub fn knn_rows(&self, ids: &[u32], k: usize) -> Result<Neighbours> {
        let n = self.len();
        if k == 0 || k >= n {
            return Err(Error::InvalidParameter {
                name: "k",
                message: format!("must be in 1..{n} for {n} points, got {k}"),
            });
        }
        let mut slot_of = vec![0u32; n];
        for (slot, &id) in self.ids.iter().enumerate() {
            slot_of[id as usize] = slot as u32;
        }
        let mut wanted = vec![false; n];
        for &id in ids {
            let slot = slot_of
                .get(id as usize)
                .ok_or_else(|| Error::InvalidParameter {
                    name: "ids",
                    message: format!("point {id} is outside the {n} indexed"),
                })?;
            let w = &mut wanted[*slot as usize];
            if *w {
                return Err(Error::InvalidParameter {
                    name: "ids",
                    message: format!("point {id} is asked twice"),
                });
            }
            *w = true;
        }
        // Rows are computed leaf by leaf in slot order, then move to the order of `ids`.
        let by_slot = self.knn_rows_by_slot(&wanted, ids.len(), k);
        let mut compact_of_slot = vec![0u32; n];
        let mut next = 0u32;
        for (c, &w) in compact_of_slot.iter_mut().zip(&wanted) {
            *c = next;
            next += u32::from(w);
        }
        Ok(rows_reordered(&by_slot, ids.len(), |i| {
            compact_of_slot[slot_of[ids[i] as usize] as usize] as usize
        }))
    }

    /// The k-NN rows of the `count` `wanted` slots, in slot order, leaves in parallel.
    fn knn_rows_by_slot(&self, wanted: &[bool], count: usize, k: usize) -> Neighbours {
        let mut indices = vec![0u32; count * k];
        let mut squared_distances = vec![0f32; count * k];
        let mut chunks = Vec::with_capacity(self.nodes.len() - self.first_leaf);
        let (mut idx_rest, mut dist_rest) =
            (indices.as_mut_slice(), squared_distances.as_mut_slice());
        for leaf in self.first_leaf..self.nodes.len() {
            let nd = &self.nodes[leaf];
            let rows = wanted[nd.start as usize..nd.end as usize]
                .iter()
                .filter(|&&w| w)
                .count();
            if rows == 0 {
                continue;
            }
            let (idx, idx_tail) = idx_rest.split_at_mut(rows * k);
            let (dist, dist_tail) = dist_rest.split_at_mut(rows * k);
            chunks.push((leaf, idx, dist));
            (idx_rest, dist_rest) = (idx_tail, dist_tail);
        }
        chunks
            .into_par_iter()
            .for_each_init(LeafScratch::default, |scratch, (leaf, idx, dist)| {
                self.leaf_knn_rows(leaf, wanted, k, idx, dist, scratch);
            });
        Neighbours {
            k,
            indices,
            squared_distances,
        }
    }

    /// For each of `queries: #Q×3`, its nearest indexed point within squared distance
    /// `radii2[i]` (inclusive; ties to the smaller index), `None` when there is none: the
    /// first result of [`SpatialIndex::nearest_within`] with k = 1, for many queries. Runs of
    /// 32 consecutive queries share one tree walk (the leaves within the largest radius of
    /// their bounding box) and scan those leaves' points with vector arithmetic, so queries
    /// in spatial order with tight radii (a Lloyd step's previous owner, say) cost a few
    /// distance evaluations each; a run whose walk finds more than 64 leaves falls back to one
    /// walk per query. Errors when the lengths differ or a query or radius is NaN.
    ///
    /// ```
    /// use meshgnn_geometry::SpatialIndex;
    /// let index = SpatialIndex::new(&[[0.0, 0.0, 0.0], [2.0, 0.0, 0.0]])?;
    /// let q = [[0.9, 0.0, 0.0], [1.0, 0.0, 0.0], [5.0, 0.0, 0.0]];
    /// assert_eq!(index.nearest_within_each(&q, &[1.0, 1.0, 1.0])?, vec![Some(0), Some(0), None]);
    /// # Ok::<(), meshgnn_geometry::Error>(())
    /// ```
    pub fn nearest_within_each(
        &self,
        queries: &[[f32; 3]],
        radii2: &[f32],
    ) -> Result<Vec<Option<u32>>> {
        if radii2.len() != queries.len() {
            return Err(Error::InvalidParameter {
                name: "radii2",
                message: format!("{} radii for {} queries", radii2.len(), queries.len()),
            });
        }
        check_finite("query", queries)?;
        if let Some(i) = radii2.iter().position(|r| r.is_nan()) {
            return Err(Error::InvalidParameter {
                name: "radii2",
                message: format!("radius {i} is NaN"),
            });
        }
        let mut nearest = vec![None; queries.len()];
        nearest
            .par_chunks_mut(QUERY_BLOCK)
            .zip(queries.par_chunks(QUERY_BLOCK))
            .zip(radii2.par_chunks(QUERY_BLOCK))
            .for_each_init(
                || {
                    (
                        Vec::new(),
                        CandidatePoints::default(),
                        Vec::new(),
                        Vec::new(),
                    )
                },
                |(candidates, others, distances, found), ((out, queries), radii2)| {
                    if self.is_empty() {
                        return;
                    }
                    let mut block = SpatialNode {
                        lo: [f32::INFINITY; 3],
                        hi: [f32::NEG_INFINITY; 3],
                        start: 0,
                        end: 0,
                        min_id: 0,
                    };
                    for q in queries {
                        for ((lo, hi), &x) in block.lo.iter_mut().zip(&mut block.hi).zip(q) {
                            *lo = lo.min(x);
                            *hi = hi.max(x);
                        }
                    }
                    let radius = radii2.iter().fold(f32::NEG_INFINITY, |m, &r| m.max(r));
                    candidates.clear();
                    // inclusive radius: any index precedes u32::MAX
                    let batched = self.collect_leaves(0, &block, (radius, u32::MAX), candidates);
                    if batched {
                        others.clear();
                        for &c in candidates.iter() {
                            let cn = &self.nodes[c];
                            let range = cn.start as usize..cn.end as usize;
                            for (p, &id) in self.points[range.clone()].iter().zip(&self.ids[range])
                            {
                                others.push(p, id);
                            }
                        }
                    }
                    for ((slot, q), &radius2) in out.iter_mut().zip(queries).zip(radii2) {
                        let query = Query {
                            q,
                            k: 1,
                            radius2,
                            exclude: None,
                        };
                        found.clear();
                        if batched {
                            others.offer_all(&query, distances, found);
                        } else {
                            self.nearest_in(0, &query, found);
                        }
                        *slot = found.first().map(|&(_, id)| id);
                    }
                },
            );
        Ok(nearest)
    }

    /// For each of `queries: #Q×3`, its `k` nearest indexed points, `#Q×k`, in parallel (a
    /// query coinciding with a point finds it at distance 0; eq. 5.5 AttRef neighbourhoods,
    /// eq. 5.6-5.7 Chamfer correspondences). Errors when `k == 0`, `k > #P`, or a query
    /// coordinate is NaN/infinite.
    ///
    /// ```
    /// use meshgnn_geometry::SpatialIndex;
    /// let index = SpatialIndex::new(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [3.0, 0.0, 0.0]])?;
    /// let nn = index.knn(&[[2.9, 0.0, 0.0]], 2)?;
    /// assert_eq!(nn.indices, vec![2, 1]);
    /// # Ok::<(), meshgnn_geometry::Error>(())
    /// ```
    pub fn knn(&self, queries: &[[f32; 3]], k: usize) -> Result<Neighbours> {
        let n = self.len();
        if k == 0 || k > n {
            return Err(Error::InvalidParameter {
                name: "k",
                message: format!("must be in 1..={n} for {n} points, got {k}"),
            });
        }
        check_finite("query", queries)?;
        Ok(self.run_queries(queries, k))
    }

    /// One k-NN query per row of `queries`, in parallel. Every query finds `k` results
    /// (callers checked `k`). Queries run in the Morton order of their cell in the index's
    /// box ([`morton_order`]), so that neighbouring queries share the tree's paths in cache
    /// whatever order the caller keeps them in; each row still lands at its query's position.
    fn run_queries(&self, queries: &[[f32; 3]], k: usize) -> Neighbours {
        let order = morton_order(queries, &self.nodes[0]);
        let mut by_order_idx = vec![0u32; queries.len() * k];
        let mut by_order_dist = vec![0.0f32; queries.len() * k];
        by_order_idx
            .par_chunks_mut(k)
            .zip(by_order_dist.par_chunks_mut(k))
            .zip(order.par_iter())
            .for_each_init(
                || Vec::with_capacity(k + 1),
                |found, ((idx, dist), &q)| {
                    self.nearest(&queries[q as usize], k, None, found);
                    for ((slot_i, slot_d), &(d, j)) in
                        idx.iter_mut().zip(dist.iter_mut()).zip(found.iter())
                    {
                        *slot_i = j;
                        *slot_d = d;
                    }
                },
            );
        let mut rank = vec![0u32; queries.len()];
        for (r, &q) in order.iter().enumerate() {
            rank[q as usize] = r as u32;
        }
        let by_order = Neighbours {
            k,
            indices: by_order_idx,
            squared_distances: by_order_dist,
        };
        rows_reordered(&by_order, queries.len(), |i| rank[i] as usize)
    }
}

/// `count` rows taken from `source`: row `i` is its row `row_of(i)`, in parallel.
fn rows_reordered(
    source: &Neighbours,
    count: usize,
    row_of: impl Fn(usize) -> usize + Sync,
) -> Neighbours {
    let k = source.k;
    let mut indices = vec![0u32; count * k];
    let mut squared_distances = vec![0f32; count * k];
    indices
        .par_chunks_mut(k)
        .zip(squared_distances.par_chunks_mut(k))
        .enumerate()
        .for_each(|(i, (idx, dist))| {
            let r = row_of(i);
            let from = r * k..(r + 1) * k;
            idx.copy_from_slice(&source.indices[from.clone()]);
            dist.copy_from_slice(&source.squared_distances[from]);
        });
    Neighbours {
        k,
        indices,
        squared_distances,
    }
}

/// The positions of `queries` sorted by the Morton (Z-order) code of their cell in a
/// `1024³` grid over the box of `root` (points outside it clamp to its faces), ties by
/// position: a spatially coherent order computed in `O(Q log Q)`.
fn morton_order(queries: &[[f32; 3]], root: &SpatialNode) -> Vec<u32> {
    const BITS: u32 = 10;
    let cells = ((1u32 << BITS) - 1) as f32;
    let scale: [f32; 3] =
        std::array::from_fn(|a| cells / (root.hi[a] - root.lo[a]).max(f32::MIN_POSITIVE));
    let spread = |mut v: u64| {
        // the bits of v, three apart
        v &= 0x3ff;
        v = (v | v << 16) & 0x0300_00ff;
        v = (v | v << 8) & 0x0300_f00f;
        v = (v | v << 4) & 0x030c_30c3;
        (v | v << 2) & 0x0924_9249
    };
    let mut keyed: Vec<(u64, u32)> = queries
        .par_iter()
        .enumerate()
        .map(|(i, q)| {
            let cell = |a: usize| ((q[a] - root.lo[a]) * scale[a]).clamp(0.0, cells) as u64;
            (
                spread(cell(0)) | spread(cell(1)) << 1 | spread(cell(2)) << 2,
                i as u32,
            )
        })
        .collect();
    keyed.par_sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}

/// Buffers of [`SpatialIndex::leaf_knn_rows`], reused across the leaves a thread handles.
#[derive(Default)]
struct LeafScratch {
    /// The current query's best so far.
    found: Vec<(f32, u32)>,
    /// Each query's `k` best inside its own leaf, `#leaf×k`.
    rows: Vec<(f32, u32)>,
    /// The leaves that may hold a neighbour of some query of the leaf.
    candidates: Vec<usize>,
    /// The points of the candidate leaves other than the query's own.
    others: CandidatePoints,
    /// The current query's squared distance to each of `others`.
    distances: Vec<f32>,
}

/// Points with their original indices, one array per coordinate.
#[derive(Default)]
struct CandidatePoints {
    xs: Vec<f32>,
    ys: Vec<f32>,
    zs: Vec<f32>,
    ids: Vec<u32>,
}

impl CandidatePoints {
    fn clear(&mut self) {
        self.xs.clear();
        self.ys.clear();
        self.zs.clear();
        self.ids.clear();
    }

    fn push(&mut self, p: &[f32; 3], id: u32) {
        self.xs.push(p[0]);
        self.ys.push(p[1]);
        self.zs.push(p[2]);
        self.ids.push(id);
    }

    /// Offers every point to `out`, the sorted `k` best so far of `query`: all distances
    /// first ([`super::squared_distance`]'s expression, lane by lane), then the few that beat the
    /// current worst.
    fn offer_all(&self, query: &Query<'_>, distances: &mut Vec<f32>, out: &mut Vec<(f32, u32)>) {
        let [qx, qy, qz] = *query.q;
        distances.clear();
        distances.extend(
            self.xs
                .iter()
                .zip(&self.ys)
                .zip(&self.zs)
                .map(|((&x, &y), &z)| {
                    let (dx, dy, dz) = (x - qx, y - qy, z - qz);
                    dx * dx + dy * dy + dz * dz
                }),
        );
        let mut worst = query.worst(out);
        for (ds, ids) in distances.chunks(8).zip(self.ids.chunks(8)) {
            // most runs of eight hold nothing nearer than the worst: one vector comparison
            let w = worst.0;
            if ds.iter().fold(true, |far, &d| far & (d > w)) {
                continue;
            }
            for (&d, &id) in ds.iter().zip(ids) {
                if d > worst.0 || !less((d, id), worst) || Some(id) == query.exclude {
                    continue;
                }
                insert_sorted(out, query.k, (d, id));
                worst = query.worst(out);
            }
        }
    }
}
