//! QEM edge-collapse decimation (Garland & Heckbert, "Surface simplification using quadric
//! error metrics", SIGGRAPH 1997), the simplification behind the thesis' mesh hierarchies
//! (ch. 2.3.2, ch. 3.3.4 "pooling ... obtained from quadric mesh simplification", Table 3.1) and
//! its QEM baseline (ch. 5-6).
//!
//! # Algorithm
//! 1. Vertices with bit-identical positions (and UVs) are welded, so triangle soups decimate
//!    as surfaces; faces that become degenerate are dropped.
//! 2. Each vertex gets the sum of the plane quadrics of its incident faces, weighted by face
//!    area; each boundary edge adds a plane through the edge perpendicular to its face,
//!    weighted by `boundary_weight · |edge|²`, so open borders stay in place.
//! 3. Every edge gets a cost `(Q_a + Q_b)(p)` at its best placement `p`: the optimum of the
//!    summed quadric when it is well conditioned, else the best of the endpoints and the
//!    midpoint (only the endpoints with `keep_original_positions`). Boundaries stay on the
//!    input's boundary polyline: an edge from an interior to a boundary vertex collapses onto
//!    the boundary vertex, and a boundary edge collapses to the best point of its segment.
//! 4. Edges are collapsed cheapest first, in passes (as meshoptimizer does): each pass scores
//!    every live edge in parallel, sorts them by `(cost, a, b)`, and collapses in that order
//!    up to the cost `1.5 ×` that of the edge ranked `(#F − target) / 2`, skipping edges whose
//!    endpoint was already changed in this pass (a per-vertex pass stamp: lazy invalidation,
//!    since only those edges' costs went stale). A collapse is rejected when it would break the
//!    link condition (the output would stop being a 2-manifold: pinched vertices, duplicated
//!    faces, a vanished component), flip a face (its normal turning by more than ~78° in the
//!    collapse, or by 90° or more from the input face it descends from) or create a zero-area
//!    face. Passes repeat until the target is reached or a pass without a cost bound
//!    collapses nothing.
//!
//!    Why passes and not one binary heap: on 1.3M triangles the heap (2M initial edges plus ~6
//!    re-scored edges per collapse) spent 14 s in cache-missing sift-downs, 10× meshoptimizer;
//!    sorted passes are cache friendly, parallel, and give the same quality (docs/qem.md).
//!
//! # Guarantees
//! - From an edge-manifold, consistently oriented input: no flipped face, no new hole, no
//!   non-manifold edge; a watertight input stays watertight.
//! - Vertices on non-manifold edges and UV-seam vertices (one position, several UVs) are never
//!   moved or removed; seams therefore never tear.
//! - The same output for any rayon thread count (the setup is parallel but order-independent,
//!   the collapse loop is sequential).
//!
//! # Attributes
//! Normals, UVs and colours are interpolated along the collapsed edge at the parameter of the
//! placement projected onto the edge (normals are re-normalised). Welding averages the normals
//! and colours of the vertices it merges (UVs are equal by construction).
//!
//! # Error units
//! [`Decimation::max_cost`] is the largest accepted cost in the priority's units (area ×
//! length²). [`Decimation::error`] is the largest accepted *normalised* cost: the cost divided
//! by the total plane weight of the quadric, i.e. the area-weighted mean squared distance of
//! the placed vertex to the original planes it absorbed (length²); [`Decimation::error_distance`]
//! is its square root, a distance in the input's units, and [`DecimationOptions::max_error`]
//! bounds that distance.

use std::cmp::Ordering;

use meshgnn_geometry::TriMesh;
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::quadric::Quadric;
use crate::weld_by_position::weld_by_position;

/// How far to simplify.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Target {
    /// Stop at (at most one above) this many triangles.
    Faces(usize),
    /// Stop at `round(ratio · #F)` triangles; `ratio` in `(0, 1]`.
    Ratio(f64),
}

impl Default for Target {
    fn default() -> Self {
        Self::Ratio(0.5)
    }
}

/// Options of [`decimate`]; update with `..Default::default()`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DecimationOptions {
    /// The face count to reach.
    pub target: Target,
    /// Reject collapses whose error distance (input units, see the module's "Error units")
    /// exceeds this; the decimation may then stop above the target.
    pub max_error: Option<f64>,
    /// Place every surviving vertex at one of the collapsed edge's endpoints, so each output
    /// vertex sits exactly at an original vertex (needed for pooling matrices).
    pub keep_original_positions: bool,
    /// Weight of the boundary-preserving planes relative to the face planes.
    pub boundary_weight: f64,
}

impl Default for DecimationOptions {
    fn default() -> Self {
        Self {
            target: Target::default(),
            max_error: None,
            keep_original_positions: false,
            boundary_weight: 100.0,
        }
    }
}

/// Why the collapse loop ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopReason {
    /// The target face count was reached.
    TargetReached,
    /// Every remaining collapse would exceed `max_error`.
    MaxError,
    /// No remaining collapse keeps the mesh manifold and unflipped.
    NoValidCollapse,
}

impl StopReason {
    /// A short snake-case name (for JSON output).
    pub fn as_str(&self) -> &'static str {
        match self {
            Self::TargetReached => "target_reached",
            Self::MaxError => "max_error",
            Self::NoValidCollapse => "no_valid_collapse",
        }
    }
}

/// The result of [`decimate`].
#[derive(Debug, Clone, PartialEq)]
pub struct Decimation {
    /// The simplified mesh, with the input's attributes carried through.
    pub mesh: TriMesh,
    /// `#V_in`: the output vertex every input vertex was merged into.
    pub vertex_map: Vec<u32>,
    /// Largest accepted normalised cost (length², see the module's "Error units").
    pub error: f64,
    /// `sqrt(error)`: a distance in the input's units.
    pub error_distance: f64,
    /// Largest accepted raw cost (area × length²), the priority's units.
    pub max_cost: f64,
    /// True when vertices with identical positions were welded first.
    pub welded: bool,
    /// Why it stopped.
    pub stop_reason: StopReason,
    /// Input triangle count.
    pub input_faces: usize,
    /// Input vertex count.
    pub input_vertices: usize,
    /// Number of edge collapses performed.
    pub collapses: usize,
}

/// Normals of faces may turn by at most `acos(0.2)` ≈ 78° in one collapse.
const MIN_NORMAL_COS: f64 = 0.2;
/// A face whose doubled area is below this fraction of its longest squared edge is degenerate.
const MIN_SLIVER: f64 = 1e-7;
/// A pass collapses edges up to this multiple of the cost of the edge ranked at its goal.
const PASS_COST_SLACK: f64 = 1.5;

/// Eq. (GH97): simplifies `mesh` by quadric-error edge collapses to `options.target`.
///
/// Fails on an empty mesh, a ratio outside `(0, 1]` or a negative/non-finite `max_error`.
///
/// ```
/// use meshgnn_geometry::subdivided_cube;
/// use meshgnn_graph::{decimate, DecimationOptions, Target};
/// let cube = subdivided_cube(4);
/// let out = decimate(&cube, &DecimationOptions { target: Target::Faces(12), ..Default::default() })?;
/// assert_eq!(out.mesh.face_count(), 12);
/// assert!(out.error_distance < 1e-5);
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn decimate(mesh: &TriMesh, options: &DecimationOptions) -> Result<Decimation> {
    decimate_with_progress(mesh, options, &mut |_| {})
}

/// [`decimate`] calling `progress(fraction in [0, 1])` as collapses proceed (about 100 times).
pub fn decimate_with_progress(
    mesh: &TriMesh,
    options: &DecimationOptions,
    progress: &mut dyn FnMut(f64),
) -> Result<Decimation> {
    let target = validate(mesh, options)?;
    let mut state = Collapser::new(mesh, options)?;
    let stop_reason = state.run(target, options, progress);
    progress(1.0);
    state.finish(mesh, stop_reason)
}

/// Checks the options and returns the target face count.
fn validate(mesh: &TriMesh, options: &DecimationOptions) -> Result<usize> {
    if mesh.face_count() == 0 {
        return Err(Error::Empty {
            what: "mesh to decimate (no triangles)",
        });
    }
    if let Some(e) = options.max_error
        && !(e >= 0.0 && e.is_finite())
    {
        return Err(Error::InvalidParameter {
            name: "max_error",
            message: format!("{e} must be a finite distance >= 0"),
        });
    }
    if !(options.boundary_weight >= 0.0 && options.boundary_weight.is_finite()) {
        return Err(Error::InvalidParameter {
            name: "boundary_weight",
            message: format!("{} must be finite and >= 0", options.boundary_weight),
        });
    }
    match options.target {
        Target::Faces(n) => Ok(n),
        Target::Ratio(r) if r > 0.0 && r <= 1.0 => {
            Ok((r * mesh.face_count() as f64).round() as usize)
        }
        Target::Ratio(r) => Err(Error::InvalidParameter {
            name: "ratio",
            message: format!("{r} is outside (0, 1]"),
        }),
    }
}

#[inline]
fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline]
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline]
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline]
fn lerp<const N: usize>(a: [f32; N], b: [f32; N], t: f64) -> [f32; N] {
    std::array::from_fn(|i| (f64::from(a[i]) * (1.0 - t) + f64::from(b[i]) * t) as f32)
}

fn normalized(v: [f32; 3]) -> [f32; 3] {
    let n = v
        .iter()
        .map(|x| f64::from(*x) * f64::from(*x))
        .sum::<f64>()
        .sqrt();
    if n > 0.0 {
        v.map(|x| (f64::from(x) / n) as f32)
    } else {
        v
    }
}

/// Where an edge collapses to.
#[derive(Debug, Clone, Copy)]
struct Placement {
    cost: f64,
    position: [f64; 3],
    /// The endpoint that survives.
    survivor: u32,
    /// Parameter of `position` along `a → b`, for attribute interpolation.
    t: f64,
}

/// The mutable state of the collapse loop: compact connectivity in flat arrays.
struct Collapser {
    positions: Vec<[f64; 3]>,
    quadrics: Vec<Quadric>,
    faces: Vec<[u32; 3]>,
    face_alive: Vec<bool>,
    /// Unit normal of each face in the input (zero for a zero-area face).
    input_normals: Vec<[f32; 3]>,
    live_faces: usize,
    /// Incident faces of vertex `v`: `refs[ref_start[v]..ref_start[v] + ref_len[v]]` (may hold
    /// dead faces, skipped on use).
    refs: Vec<u32>,
    ref_start: Vec<usize>,
    ref_len: Vec<u32>,
    vertex_alive: Vec<bool>,
    /// The pass in which each vertex last changed (0: never).
    touched: Vec<u32>,
    parent: Vec<u32>,
    locked: Vec<bool>,
    boundary: Vec<bool>,
    normals: Option<Vec<[f32; 3]>>,
    uvs: Option<Vec<[f32; 2]>>,
    colors: Option<Vec<[f32; 3]>>,
    weld_map: Vec<u32>,
    welded: bool,
    /// The setup's edges (manifold ones), scored in the first pass.
    initial_edges: Vec<(u32, u32)>,
    mark: Vec<u32>,
    stamp: u32,
    scratch_faces: Vec<u32>,
    scratch_pairs: Vec<[u32; 2]>,
    max_cost: f64,
    max_error: f64,
    collapses: usize,
    keep_original_positions: bool,
}

impl Collapser {
    fn new(mesh: &TriMesh, options: &DecimationOptions) -> Result<Self> {
        let welding = weld_by_position(mesh.vertices(), mesh.uvs());
        let reps = &welding.representatives;
        let n = reps.len();
        let positions: Vec<[f64; 3]> = reps
            .par_iter()
            .map(|&r| mesh.vertices()[r as usize].map(f64::from))
            .collect();
        let faces: Vec<[u32; 3]> = mesh
            .triangles()
            .par_iter()
            .map(|t| t.map(|v| welding.map[v as usize]))
            .filter(|[a, b, c]| a != b && b != c && a != c)
            .collect();

        // Attributes of welded vertices: UVs equal by construction; normals/colours averaged.
        let average3 = |values: &[[f32; 3]], unit: bool| -> Vec<[f32; 3]> {
            let mut sum = vec![[0f64; 3]; n];
            let mut count = vec![0u32; n];
            for (i, v) in values.iter().enumerate() {
                let w = welding.map[i] as usize;
                for k in 0..3 {
                    sum[w][k] += f64::from(v[k]);
                }
                count[w] += 1;
            }
            sum.iter()
                .zip(&count)
                .map(|(s, &c)| {
                    let m = s.map(|x| (x / f64::from(c.max(1))) as f32);
                    if unit { normalized(m) } else { m }
                })
                .collect()
        };
        let normals = mesh.normals().map(|v| average3(v, true));
        let colors = mesh.colors().map(|v| average3(v, false));
        let uvs = mesh
            .uvs()
            .map(|u| reps.iter().map(|&r| u[r as usize]).collect::<Vec<_>>());

        // Vertex → face incidence (CSR, faces in increasing order).
        let mut ref_len = vec![0u32; n];
        for f in &faces {
            for &v in f {
                ref_len[v as usize] += 1;
            }
        }
        let mut ref_start = Vec::with_capacity(n);
        let mut total = 0usize;
        for &len in &ref_len {
            ref_start.push(total);
            total += len as usize;
        }
        let mut refs = vec![0u32; total];
        let mut fill = ref_start.clone();
        for (fi, f) in faces.iter().enumerate() {
            for &v in f {
                refs[fill[v as usize]] = fi as u32;
                fill[v as usize] += 1;
            }
        }

        // Area-weighted face plane quadrics, summed per vertex in CSR order (deterministic).
        // (Face quadrics are recomputed per incident vertex rather than stored: 3× the
        // arithmetic, but no 80-byte-per-face array at the memory peak.)
        let face_normal = |f: u32| {
            let [p0, p1, p2] = faces[f as usize].map(|v| positions[v as usize]);
            (cross(sub(p1, p0), sub(p2, p0)), p0)
        };
        let input_normals: Vec<[f32; 3]> = (0..faces.len() as u32)
            .into_par_iter()
            .map(|f| {
                let (n, _) = face_normal(f);
                let len = dot(n, n).sqrt();
                if len > 0.0 {
                    n.map(|x| (x / len) as f32)
                } else {
                    [0.0; 3]
                }
            })
            .collect();
        let mut quadrics: Vec<Quadric> = (0..n)
            .into_par_iter()
            .map(|v| {
                let start = ref_start[v];
                refs[start..start + ref_len[v] as usize].iter().fold(
                    Quadric::default(),
                    |acc, &f| {
                        let (normal, point) = face_normal(f);
                        acc + Quadric::from_plane(normal, point, 0.5 * dot(normal, normal).sqrt())
                    },
                )
            })
            .collect();

        // Undirected edges `(a < b, face count, first face)`, enumerated per vertex from the
        // incidence lists (parallel, no global sort): boundary and non-manifold detection.
        let grouped: Vec<(u32, u32, u32, u32)> = (0..n)
            .into_par_iter()
            .flat_map_iter(|a| {
                let start = ref_start[a];
                let mut local: Vec<(u32, u32)> = Vec::with_capacity(2 * ref_len[a] as usize);
                for &f in &refs[start..start + ref_len[a] as usize] {
                    for x in faces[f as usize] {
                        if x as usize > a {
                            local.push((x, f));
                        }
                    }
                }
                local.sort_unstable();
                let mut out = Vec::with_capacity(local.len());
                let mut i = 0;
                while i < local.len() {
                    let mut j = i + 1;
                    while j < local.len() && local[j].0 == local[i].0 {
                        j += 1;
                    }
                    out.push((a as u32, local[i].0, (j - i) as u32, local[i].1));
                    i = j;
                }
                out
            })
            .collect();
        let mut locked = welding.seam.clone();
        let mut boundary = vec![false; n];
        let mut edges: Vec<(u32, u32)> = Vec::with_capacity(grouped.len());
        for &(a, b, count, f) in &grouped {
            match count {
                1 => {
                    boundary[a as usize] = true;
                    boundary[b as usize] = true;
                    let [p0, p1, p2] = faces[f as usize].map(|v| positions[v as usize]);
                    let normal = cross(sub(p1, p0), sub(p2, p0));
                    let (pa, pb) = (positions[a as usize], positions[b as usize]);
                    let e = sub(pb, pa);
                    let w = options.boundary_weight * dot(e, e);
                    let q = Quadric::from_plane(cross(e, normal), pa, w);
                    quadrics[a as usize] += q;
                    quadrics[b as usize] += q;
                    edges.push((a, b));
                }
                2 => edges.push((a, b)),
                _ => {
                    locked[a as usize] = true;
                    locked[b as usize] = true;
                }
            }
        }
        drop(grouped);

        let live_faces = faces.len();
        Ok(Self {
            positions,
            quadrics,
            face_alive: vec![true; faces.len()],
            input_normals,
            faces,
            live_faces,
            refs,
            ref_start,
            ref_len,
            vertex_alive: vec![true; n],
            touched: vec![0; n],
            parent: (0..n as u32).collect(),
            locked,
            boundary,
            normals,
            uvs,
            colors,
            welded: welding.merged_any(),
            weld_map: welding.map,
            initial_edges: edges,
            mark: vec![0; n],
            stamp: 0,
            scratch_faces: Vec::new(),
            scratch_pairs: Vec::new(),
            max_cost: 0.0,
            max_error: 0.0,
            collapses: 0,
            keep_original_positions: options.keep_original_positions,
        })
    }

    /// The cheapest placement of collapsing edge `(a, b)`; `None` when both ends are locked.
    fn placement(&self, a: u32, b: u32) -> Option<Placement> {
        let (ia, ib) = (a as usize, b as usize);
        let (la, lb) = (self.locked[ia], self.locked[ib]);
        if la && lb {
            return None;
        }
        let q = self.quadrics[ia] + self.quadrics[ib];
        let (pa, pb) = (self.positions[ia], self.positions[ib]);
        let mut best = Placement {
            cost: f64::INFINITY,
            position: pa,
            survivor: a,
            t: 0.0,
        };
        let mut consider = |position: [f64; 3], survivor: u32, t: f64| {
            let cost = q.evaluate(position);
            if cost < best.cost {
                best = Placement {
                    cost,
                    position,
                    survivor,
                    t,
                };
            }
        };
        let (ba, bb) = (self.boundary[ia], self.boundary[ib]);
        if la || (ba && !bb) {
            consider(pa, a, 0.0);
        } else if lb || (bb && !ba) {
            consider(pb, b, 1.0);
        } else if self.keep_original_positions {
            consider(pa, a, 0.0);
            consider(pb, b, 1.0);
        } else if ba && bb {
            // Along a boundary edge: the minimiser on the segment keeps the vertex on the
            // input's boundary polyline. `Q(a + t·e)` is quadratic in `t`; fit it from 3 values.
            let at = |t: f64| std::array::from_fn(|i| pa[i] + t * (pb[i] - pa[i]));
            let (f0, fh, f1) = (q.evaluate(pa), q.evaluate(at(0.5)), q.evaluate(pb));
            let (lin, quad) = (4.0 * fh - 3.0 * f0 - f1, 2.0 * f1 - 4.0 * fh + 2.0 * f0);
            if quad > 0.0 {
                let t = (-lin / (2.0 * quad)).clamp(0.0, 1.0);
                consider(at(t), a, t);
            }
            consider(pa, a, 0.0);
            consider(pb, b, 1.0);
            consider(at(0.5), a, 0.5);
        } else {
            if let Some(p) = q.optimal_point() {
                let e = sub(pb, pa);
                let len2 = dot(e, e);
                let t = if len2 > 0.0 {
                    (dot(sub(p, pa), e) / len2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                consider(p, a, t);
            }
            consider(pa, a, 0.0);
            consider(pb, b, 1.0);
            let mid = [
                0.5 * (pa[0] + pb[0]),
                0.5 * (pa[1] + pb[1]),
                0.5 * (pa[2] + pb[2]),
            ];
            consider(mid, a, 0.5);
        }
        best.cost.is_finite().then_some(best)
    }

    fn incident(&self, v: u32) -> std::ops::Range<usize> {
        let start = self.ref_start[v as usize];
        start..start + self.ref_len[v as usize] as usize
    }

    fn next_stamp(&mut self) -> u32 {
        if self.stamp >= u32::MAX - 2 {
            self.mark.iter_mut().for_each(|m| *m = 0);
            self.stamp = 0;
        }
        self.stamp += 2;
        self.stamp
    }

    /// Link condition, boundary, duplicate-face, flip and degeneracy checks for collapsing
    /// `(a, b)` to `p`.
    fn collapse_allowed(&mut self, a: u32, b: u32, p: [f64; 3]) -> bool {
        let s1 = self.next_stamp();
        let s2 = s1 + 1;
        let mut count_a = 0usize;
        for k in self.incident(a) {
            let f = self.refs[k] as usize;
            if !self.face_alive[f] {
                continue;
            }
            count_a += 1;
            for v in self.faces[f] {
                if v != a {
                    self.mark[v as usize] = s1;
                }
            }
        }
        let (mut shared, mut common, mut count_b) = (0usize, 0usize, 0usize);
        for k in self.incident(b) {
            let f = self.refs[k] as usize;
            if !self.face_alive[f] {
                continue;
            }
            count_b += 1;
            let face = self.faces[f];
            if face.contains(&a) {
                shared += 1;
            }
            for v in face {
                if v != a && v != b && self.mark[v as usize] == s1 {
                    self.mark[v as usize] = s2;
                    common += 1;
                }
            }
        }
        if shared == 0 || shared > 2 || common != shared || count_a + count_b == 2 * shared {
            return false;
        }
        if shared == 2 && self.boundary[a as usize] && self.boundary[b as usize] {
            return false;
        }
        // Duplicate faces: an opposite edge present around both a and b.
        self.scratch_pairs.clear();
        for k in self.incident(a) {
            let f = self.refs[k] as usize;
            let face = self.faces[f];
            if self.face_alive[f] && !face.contains(&b) {
                let [x, y] = others(face, a);
                self.scratch_pairs.push([x.min(y), x.max(y)]);
            }
        }
        for k in self.incident(b) {
            let f = self.refs[k] as usize;
            let face = self.faces[f];
            if self.face_alive[f] && !face.contains(&a) {
                let [x, y] = others(face, b);
                if self.scratch_pairs.contains(&[x.min(y), x.max(y)]) {
                    return false;
                }
            }
        }
        // Flips and degenerate faces around both ends.
        for (moving, other) in [(a, b), (b, a)] {
            for k in self.incident(moving) {
                let f = self.refs[k] as usize;
                let face = self.faces[f];
                if !self.face_alive[f] || face.contains(&other) {
                    continue;
                }
                let old = face.map(|v| self.positions[v as usize]);
                let new = face.map(|v| {
                    if v == moving {
                        p
                    } else {
                        self.positions[v as usize]
                    }
                });
                let n_old = cross(sub(old[1], old[0]), sub(old[2], old[0]));
                let n_new = cross(sub(new[1], new[0]), sub(new[2], new[0]));
                let len_new2 = dot(n_new, n_new);
                let longest2 = (0..3)
                    .map(|i| {
                        let e = sub(new[(i + 1) % 3], new[i]);
                        dot(e, e)
                    })
                    .fold(0.0, f64::max);
                // Also rejects NaN (written so that a NaN compares as degenerate).
                if len_new2.sqrt().partial_cmp(&(MIN_SLIVER * longest2)) != Some(Ordering::Greater)
                {
                    return false;
                }
                let d = dot(n_old, n_new);
                let len_old2 = dot(n_old, n_old);
                if len_old2 > 0.0 && d < MIN_NORMAL_COS * (len_old2 * len_new2).sqrt() {
                    return false;
                }
                // Nor may it turn past 90° from the input face it descends from.
                if dot(self.input_normals[f].map(f64::from), n_new) <= 0.0 {
                    return false;
                }
            }
        }
        true
    }

    /// Collapses `(a, b)` at `placement` and updates the connectivity; stamps the survivor
    /// with `pass`.
    fn collapse(&mut self, a: u32, b: u32, placement: Placement, pass: u32) {
        let s = placement.survivor;
        let r = if s == a { b } else { a };
        let (is, ir) = (s as usize, r as usize);
        // Faces of r: remove those shared with s, re-point the others to s.
        self.scratch_faces.clear();
        for k in self.incident(r) {
            let f = self.refs[k] as usize;
            if !self.face_alive[f] {
                continue;
            }
            if self.faces[f].contains(&s) {
                self.face_alive[f] = false;
                self.live_faces -= 1;
            } else {
                for v in &mut self.faces[f] {
                    if *v == r {
                        *v = s;
                    }
                }
                self.scratch_faces.push(f as u32);
            }
        }
        // New incidence list of s: its live faces, then r's, appended to `refs`.
        let start = self.refs.len();
        for k in self.incident(s) {
            let f = self.refs[k];
            if self.face_alive[f as usize] {
                self.refs.push(f);
            }
        }
        self.refs.extend_from_slice(&self.scratch_faces);
        self.ref_start[is] = start;
        self.ref_len[is] = (self.refs.len() - start) as u32;
        self.ref_len[ir] = 0;

        // Attributes at the placement's parameter along a → b.
        let t = placement.t;
        let (ia, ib) = (a as usize, b as usize);
        if let Some(n) = &mut self.normals {
            n[is] = normalized(lerp(n[ia], n[ib], t));
        }
        if let Some(u) = &mut self.uvs {
            u[is] = lerp(u[ia], u[ib], t);
        }
        if let Some(c) = &mut self.colors {
            c[is] = lerp(c[ia], c[ib], t);
        }
        let q = self.quadrics[is] + self.quadrics[ir];
        self.quadrics[is] = q;
        self.positions[is] = placement.position;
        self.boundary[is] |= self.boundary[ir];
        self.vertex_alive[ir] = false;
        self.parent[ir] = s;
        self.touched[is] = pass;
        self.collapses += 1;
        self.max_cost = self.max_cost.max(placement.cost);
        let weight = q.weight();
        if weight > 0.0 {
            self.max_error = self.max_error.max(placement.cost / weight);
        }

        if self.refs.len() > 4 * self.faces.len() + 1024 {
            self.compact_refs();
        }
    }

    /// Rewrites `refs` with only the live faces of live vertices.
    fn compact_refs(&mut self) {
        let mut refs = Vec::with_capacity(3 * self.live_faces);
        for v in 0..self.ref_start.len() {
            let range = self.incident(v as u32);
            let start = refs.len();
            refs.extend(
                self.refs[range]
                    .iter()
                    .copied()
                    .filter(|&f| self.face_alive[f as usize]),
            );
            self.ref_start[v] = start;
            self.ref_len[v] = (refs.len() - start) as u32;
        }
        self.refs = refs;
    }

    /// The collapse passes; returns why they stopped.
    fn run(
        &mut self,
        target: usize,
        options: &DecimationOptions,
        progress: &mut dyn FnMut(f64),
    ) -> StopReason {
        let max_error2 = options.max_error.map(|e| e * e);
        let initial = self.live_faces;
        let to_remove = initial.saturating_sub(target).max(1) as f64;
        let mut rejected_for_error = false;
        let mut bounded = true;
        let mut pass = 0u32;
        let initial_edges = std::mem::take(&mut self.initial_edges);
        let mut candidates = self.score(&initial_edges);
        drop(initial_edges);
        let mut touched_list: Vec<u32> = Vec::new();
        while self.live_faces > target {
            pass += 1;
            if pass > 1 {
                candidates = self.rescore(candidates, &touched_list, pass - 1);
            }
            touched_list.clear();
            let goal = (self.live_faces - target).div_ceil(2);
            let limit = match candidates.get(goal) {
                Some(c) if bounded => PASS_COST_SLACK * c.0,
                _ => f64::INFINITY,
            };
            let collapses_before = self.collapses;
            for &(cost, a, b) in &candidates {
                if self.live_faces <= target || cost > limit {
                    break;
                }
                let (ia, ib) = (a as usize, b as usize);
                if !self.vertex_alive[ia]
                    || !self.vertex_alive[ib]
                    || self.touched[ia] == pass
                    || self.touched[ib] == pass
                {
                    continue;
                }
                // Untouched endpoints: the placement is the one scored above.
                let Some(placement) = self.placement(a, b) else {
                    continue;
                };
                if let Some(limit) = max_error2 {
                    let weight = (self.quadrics[ia] + self.quadrics[ib]).weight();
                    if weight > 0.0 && placement.cost / weight > limit {
                        rejected_for_error = true;
                        continue;
                    }
                }
                if !self.collapse_allowed(a, b, placement.position) {
                    continue;
                }
                self.collapse(a, b, placement, pass);
                touched_list.push(placement.survivor);
            }
            progress((initial - self.live_faces) as f64 / to_remove);
            if self.collapses == collapses_before {
                if !bounded || limit.is_infinite() {
                    break;
                }
                // The cost bound admitted only rejected collapses: retry without it.
                bounded = false;
            } else {
                bounded = true;
            }
        }
        if self.live_faces <= target {
            StopReason::TargetReached
        } else if rejected_for_error {
            StopReason::MaxError
        } else {
            StopReason::NoValidCollapse
        }
    }

    /// `(cost, a, b)` of every collapsible edge of `edges`, scored in parallel, sorted.
    fn score(&self, edges: &[(u32, u32)]) -> Vec<(f64, u32, u32)> {
        let mut candidates: Vec<(f64, u32, u32)> = edges
            .par_iter()
            .filter_map(|&(a, b)| self.placement(a, b).map(|p| (p.cost, a, b)))
            .collect();
        // (cost, a, b) is unique per edge, so the unstable sort is deterministic.
        candidates.par_sort_unstable_by(by_cost);
        candidates
    }

    /// The next pass's candidates: the previous ones whose endpoints are alive and were not
    /// changed in pass `pass` (their cost is unchanged), merged with the re-scored edges
    /// around the vertices `touched` in that pass.
    fn rescore(
        &mut self,
        previous: Vec<(f64, u32, u32)>,
        touched: &[u32],
        pass: u32,
    ) -> Vec<(f64, u32, u32)> {
        let valid = |v: u32| self.vertex_alive[v as usize] && self.touched[v as usize] != pass;
        let kept: Vec<(f64, u32, u32)> = previous
            .into_iter()
            .filter(|c| valid(c.1) && valid(c.2))
            .collect();
        let mut fresh_edges = Vec::new();
        for &s in touched {
            if !self.vertex_alive[s as usize] {
                continue;
            }
            let stamp = self.next_stamp();
            for k in self.incident(s) {
                let f = self.refs[k] as usize;
                if !self.face_alive[f] {
                    continue;
                }
                for v in self.faces[f] {
                    // An edge between two touched vertices is emitted once, by the smaller.
                    if v != s
                        && self.mark[v as usize] != stamp
                        && (self.touched[v as usize] != pass || s < v)
                    {
                        self.mark[v as usize] = stamp;
                        fresh_edges.push((s.min(v), s.max(v)));
                    }
                }
            }
        }
        let fresh = self.score(&fresh_edges);
        let mut merged = Vec::with_capacity(kept.len() + fresh.len());
        let (mut i, mut j) = (0, 0);
        while i < kept.len() && j < fresh.len() {
            if by_cost(&kept[i], &fresh[j]).is_le() {
                merged.push(kept[i]);
                i += 1;
            } else {
                merged.push(fresh[j]);
                j += 1;
            }
        }
        merged.extend_from_slice(&kept[i..]);
        merged.extend_from_slice(&fresh[j..]);
        merged
    }

    /// Builds the output mesh and the vertex map.
    fn finish(self, mesh: &TriMesh, stop_reason: StopReason) -> Result<Decimation> {
        let n = self.positions.len();
        let mut new_index = vec![u32::MAX; n];
        let mut vertices = Vec::new();
        for (v, index) in new_index.iter_mut().enumerate() {
            if self.vertex_alive[v] {
                *index = vertices.len() as u32;
                vertices.push(self.positions[v].map(|x| x as f32));
            }
        }
        let keep = |v: usize| self.vertex_alive[v];
        let gather3 = |values: &Option<Vec<[f32; 3]>>| {
            values.as_ref().map(|x| {
                (0..n)
                    .filter(|&v| keep(v))
                    .map(|v| x[v])
                    .collect::<Vec<_>>()
            })
        };
        let triangles: Vec<[u32; 3]> = self
            .faces
            .iter()
            .zip(&self.face_alive)
            .filter(|(_, alive)| **alive)
            .map(|(f, _)| f.map(|v| new_index[v as usize]))
            .collect();
        // Each welded vertex's surviving representative, memoised so the work stays linear.
        let mut root = vec![u32::MAX; n];
        for v in 0..n {
            let mut r = v;
            while !self.vertex_alive[r] && root[r] == u32::MAX {
                r = self.parent[r] as usize;
            }
            let found = if self.vertex_alive[r] {
                r as u32
            } else {
                root[r]
            };
            let mut w = v;
            while !self.vertex_alive[w] && root[w] == u32::MAX {
                root[w] = found;
                w = self.parent[w] as usize;
            }
            root[v] = found;
        }
        let vertex_map = self
            .weld_map
            .iter()
            .map(|&w| new_index[root[w as usize] as usize])
            .collect();
        let mut out = TriMesh::new(vertices, triangles)?;
        if let Some(normals) = gather3(&self.normals) {
            out = out.with_normals(normals)?;
        }
        if let Some(uvs) = &self.uvs {
            out = out.with_uvs((0..n).filter(|&v| keep(v)).map(|v| uvs[v]).collect())?;
        }
        if let Some(colors) = gather3(&self.colors) {
            out = out.with_colors(colors)?;
        }
        Ok(Decimation {
            mesh: out,
            vertex_map,
            error: self.max_error,
            error_distance: self.max_error.sqrt(),
            max_cost: self.max_cost,
            welded: self.welded,
            stop_reason,
            input_faces: mesh.face_count(),
            input_vertices: mesh.vertex_count(),
            collapses: self.collapses,
        })
    }
}

/// Candidate order: cost, then vertex ids (a total order, so sorting is deterministic).
fn by_cost(x: &(f64, u32, u32), y: &(f64, u32, u32)) -> Ordering {
    x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)).then(x.2.cmp(&y.2))
}

/// The two vertices of `face` other than `v`, in winding order after `v`.
fn others(face: [u32; 3], v: u32) -> [u32; 2] {
    if face[0] == v {
        [face[1], face[2]]
    } else if face[1] == v {
        [face[2], face[0]]
    } else {
        [face[0], face[1]]
    }
}
