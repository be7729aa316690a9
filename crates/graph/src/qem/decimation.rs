//! QEM edge-collapse decimation (Garland & Heckbert, "Surface simplification using quadric
//! error metrics", SIGGRAPH 1997), the simplification behind the thesis' mesh hierarchies
//! (ch. 2.3.2, ch. 3.3.4 "pooling ... obtained from quadric mesh simplification", Table 3.1) and
//! its QEM baseline (ch. 5-6).
//!
//! # Algorithm
//! 1. Vertices with bit-identical positions (and UVs) are welded, so triangle soups decimate
//!    as surfaces; faces that become degenerate, and faces repeating an earlier face's three
//!    vertices (doubled sheets of scans), are dropped.
//! 2. Each vertex gets the sum of the plane quadrics of its incident faces, weighted by face
//!    area; each boundary edge adds a plane through the edge perpendicular to its face,
//!    weighted by `boundary_weight · |edge|²`, so open borders stay in place.
//! 3. Every edge gets a cost `(Q_a + Q_b)(p)` at its best placement `p`: the optimum of the
//!    summed quadric when it is well conditioned, else the best of the endpoints and the
//!    midpoint (only the endpoints with `keep_original_positions`). Boundaries stay on the
//!    input's boundary polyline: an edge from an interior to a boundary vertex collapses onto
//!    the boundary vertex, and a boundary edge collapses to the best point of its segment.
//! 4. Edges are collapsed cheapest first, in passes (as meshoptimizer does): the first pass
//!    scores every edge in parallel and radix-sorts them by cost (ties in a fixed order); it
//!    collapses in that order up to the cost `1.5 ×` that of the edge ranked
//!    `(#F − target) / 2`, skipping edges whose endpoint was already changed in this pass (a
//!    one-bit-per-vertex "changed" set: lazy invalidation, since only those edges' costs went
//!    stale). The next pass keeps the still-valid sorted candidates and merges in the
//!    re-scored edges around the changed vertices (visited in vertex order, for locality).
//!    The loop itself is sequential (on a pool thread, which joins each batch's parallel
//!    work without a wake-up), but the placement and checks of the next batch of
//!    candidates are evaluated speculatively in parallel (`speculation.rs`) and reused
//!    unless an earlier collapse of the batch touched what they read, so the result is that
//!    of the sequential loop; fans are warmed level by level before they are walked
//!    (`memory_warmup.rs`). A collapse is rejected when it would break the link
//!    condition (the output would stop being a 2-manifold: pinched vertices, duplicated faces,
//!    a vanished component), flip a face (its normal turning by more than ~78° in the
//!    collapse), fold a face away from the input surface it stands for (more than ~78° from
//!    the summed input normals of its corners' regions) or create a zero-area face.
//!    Positions are rounded to `f32` before they are scored and checked, so the checks see
//!    exactly the output. Passes repeat until the target is reached or a pass without a cost
//!    bound collapses nothing.
//!
//!    Why passes and not one binary heap: on 1.3M triangles the heap (2M initial edges plus ~6
//!    re-scored edges per collapse) spent 14 s in cache-missing sift-downs, 10× meshoptimizer;
//!    sorted passes are cache friendly, parallel, and give the same quality (docs/qem.md).
//!
//! 5. A mesh of at least 100 000 faces decimated to at most a third of them is cut in eight
//!    spatial blocks, which the threads take as they free up, the faces across the cuts kept
//!    in each of their blocks with their corners; the joined blocks are then decimated to the
//!    target from the quadrics the blocks summed (`spatial_blocks.rs`: the loop waits on
//!    memory, so a second loop gains where a second thread in one loop does not; docs/qem.md).
//!
//! # Guarantees
//! - From an edge-manifold, consistently oriented input: no flipped face, no new hole, no
//!   non-manifold edge; a watertight input stays watertight. Every output face stays within
//!   ~78° of the input surface around its corners (a noisy sphere whose input faces all point
//!   outwards decimates to one whose faces all point outwards).
//! - From any input: no edge ends with more faces than it had (an edge with three or more
//!   faces merges only with edges such that the result has no more than either had, or 2), so
//!   no non-manifold edge appears and none gets worse. Vertices on non-manifold edges stay
//!   where they are and are removed only along a non-manifold edge, onto its other end.
//! - UV-seam vertices (one position, several UVs: *twins*) never move; one is removed only
//!   along the seam, onto its neighbour there, together with each of its twins, each onto a
//!   twin of that neighbour along its own chart's seam edge (all collapses checked, all or
//!   none done; twins share one quadric, the face planes of all their charts). Seams
//!   therefore never tear; a vertex where three charts meet stays unless each of its twins
//!   has such an edge.
//! - The same output for any rayon thread count (the setup is parallel but order-independent,
//!   each collapse loop is sequential, and the blocks are cut by position).
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

use std::borrow::Cow;

use meshgnn_geometry::TriMesh;
use rayon::prelude::*;

use super::candidates::{Candidate, cost_key, key_cost, merge_sorted, radix_sort};
use super::collapse_checks::CheckScratch;
use super::collapser::{Collapser, DEAD, Placement};
use super::quadric::Quadric;
use super::spatial_blocks::decimate_in_blocks;
use super::speculation::{Speculations, Verdict};
use super::vertex_bits::VertexBits;
use crate::error::{Error, Result};

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

impl Target {
    /// The vertex count a simplifier that selects vertices keeps of `mesh` for this target,
    /// at least 3: `R·V` for a ratio, `N·V/F` for a face count (a closed surface has about
    /// two faces per vertex, so the face count lands near the target).
    pub fn vertex_count(&self, mesh: &TriMesh) -> usize {
        let v = mesh.vertex_count() as f64;
        let kept = match *self {
            Self::Ratio(r) => r * v,
            Self::Faces(n) => n as f64 * v / mesh.face_count().max(1) as f64,
        };
        (kept.round() as usize).clamp(3, mesh.vertex_count().max(3))
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

/// Survivors re-scored by one parallel task.
const RESCORE_CHUNK: usize = 256;

/// Survivors whose fans are warmed together (`Collapser::warm`) before their edges are
/// re-scored.
const RESCORE_WARM: usize = 32;

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
    decimate_keeping(mesh, options, &[], progress)
}

/// [`decimate_with_progress`] that never removes nor moves the input vertices `keep`
/// (landmarks, or vertices chosen beforehand): every other vertex may collapse onto them, and
/// no edge between two of them collapses. With `keep_original_positions` and a target of one
/// face it removes every other vertex it can: the QEM connectivity of the kept vertices.
/// Errors as [`decimate`] and on a vertex outside the mesh.
///
/// ```
/// use meshgnn_geometry::icosphere;
/// use meshgnn_graph::{decimate_keeping, DecimationOptions, Target};
/// let sphere = icosphere(2); // 162 vertices
/// let keep: Vec<u32> = (0..162).step_by(4).collect();
/// let options = DecimationOptions { target: Target::Faces(1), ..Default::default() };
/// let out = decimate_keeping(&sphere, &options, &keep, &mut |_| {})?;
/// for &v in &keep {
///     let o = out.vertex_map[v as usize] as usize;
///     assert_eq!(out.mesh.vertices()[o], sphere.vertices()[v as usize]);
/// }
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn decimate_keeping(
    mesh: &TriMesh,
    options: &DecimationOptions,
    keep: &[u32],
    progress: &mut dyn FnMut(f64),
) -> Result<Decimation> {
    let target = validate(mesh, options)?;
    let blocks = match keep {
        [] => decimate_in_blocks(mesh, options, target, progress),
        _ => None,
    };
    blocks.unwrap_or_else(|| decimate_whole(Cow::Borrowed(mesh), options, keep, None, progress))
}

/// [`decimate_keeping`] in one collapse loop over the whole mesh, from the quadrics `given`
/// per input vertex (else those of its faces and borders). A mesh given owned is freed once
/// the loop's state holds its data.
pub(super) fn decimate_whole(
    mesh: Cow<'_, TriMesh>,
    options: &DecimationOptions,
    keep: &[u32],
    given: Option<&[Quadric]>,
    progress: &mut dyn FnMut(f64),
) -> Result<Decimation> {
    let (state, stop_reason) = collapse_whole(mesh, options, keep, given, None, progress)?;
    state.finish(stop_reason)
}

/// [`decimate_whole`], with the quadrics of the vertices left, in output order: what a later
/// pass over the output starts from. No collapse costing more than `cost_cap` (in the
/// priority's units, [`Decimation::max_cost`]) is made: the loop stops short of the target
/// there.
pub(super) fn decimate_whole_with_quadrics(
    mesh: Cow<'_, TriMesh>,
    options: &DecimationOptions,
    keep: &[u32],
    cost_cap: Option<f64>,
    progress: &mut dyn FnMut(f64),
) -> Result<(Decimation, Vec<Quadric>)> {
    let (state, stop_reason) = collapse_whole(mesh, options, keep, None, cost_cap, progress)?;
    let quadrics = state.survivor_quadrics();
    Ok((state.finish(stop_reason)?, quadrics))
}

/// The collapse loop of [`decimate_whole`], up to the output.
fn collapse_whole(
    mesh: Cow<'_, TriMesh>,
    options: &DecimationOptions,
    keep: &[u32],
    given: Option<&[Quadric]>,
    cost_cap: Option<f64>,
    progress: &mut dyn FnMut(f64),
) -> Result<(Collapser, StopReason)> {
    let target = validate(&mesh, options)?;
    let mut state = Collapser::new(&mesh, options, keep, given)?;
    drop(mesh);
    let stop_reason = run(&mut state, target, options, cost_cap, progress);
    progress(1.0);
    Ok((state, stop_reason))
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

/// The number of candidates evaluated together (speculatively, in parallel on `threads`) for a
/// mesh with `live_faces` faces: large enough to amortise the parallel dispatch, small enough
/// that few verdicts go stale within a batch (a collapse changes 2 of the ~`live_faces / 2`
/// vertices) and that the collapses still find the evaluated fans in cache (1024 ran ~20%
/// faster than 4096 on 1.3M faces). One thread has no dispatch to amortise: a batch of 128
/// keeps its fans in the core's own cache until they are collapsed (the blocks of 1.3M faces
/// ran 6-10 % faster than with 1024; the output is the same for any batch size).
fn batch_size(live_faces: usize, threads: usize) -> usize {
    let most = if threads > 1 { 1024 } else { 128 };
    (live_faces / 256).clamp(64, most)
}

/// The collapse passes over `state`, none costing more than `cost_cap`; returns why they
/// stopped.
fn run(
    state: &mut Collapser,
    target: usize,
    options: &DecimationOptions,
    cost_cap: Option<f64>,
    progress: &mut dyn FnMut(f64),
) -> StopReason {
    let max_error2 = options.max_error.map(|e| e * e);
    let cap = cost_cap.map_or(u32::MAX, cost_key);
    let initial = state.live_faces;
    let to_remove = initial.saturating_sub(target).max(1) as f64;
    let mut bounded = true;
    let mut pass = 0u32;
    let initial_edges = std::mem::take(&mut state.initial_edges);
    let mut candidates = score(state, initial_edges);
    let mut loop_state = LoopState::new(state.verts.len());
    while state.live_faces > target {
        pass += 1;
        if pass > 1 {
            candidates = rescore(state, candidates, &loop_state.touched, &loop_state.changed);
        }
        loop_state.touched.clear();
        loop_state.changed.clear();
        let goal = (state.live_faces - target).div_ceil(2);
        let limit = match candidates.get(goal) {
            Some(c) if bounded => Some(cost_key(PASS_COST_SLACK * key_cost(c.key))),
            _ => None,
        };
        // Candidates beyond the cost bound or the cap are never tried.
        let bound = limit.map_or(cap, |l| l.min(cap));
        let usable = candidates.partition_point(|c| c.key <= bound);
        let collapses_before = state.collapses;
        let mut start = 0;
        while start < usable && state.live_faces > target {
            // The batches run on a thread of rayon's pool: each batch's parallel evaluation
            // then starts and ends there, without waking this (possibly outside) thread twice
            // per batch (13-20 % less time on 1.3M faces, docs/qem.md). The incidence lists
            // are compacted back here, so their new buffer comes from this thread's allocator
            // arena, where the old one returns (from a pool thread's: +15 MB peak).
            let threads = rayon::current_num_threads();
            rayon::scope(|_| {
                while start < usable && state.live_faces > target && !state.refs_full() {
                    let end = usable.min(start + batch_size(state.live_faces, threads));
                    collapse_batch(
                        state,
                        &candidates[start..end],
                        target,
                        max_error2,
                        &mut loop_state,
                    );
                    start = end;
                }
            });
            if state.refs_full() {
                state.compact_refs();
            }
        }
        progress((initial - state.live_faces) as f64 / to_remove);
        if state.collapses == collapses_before {
            if !bounded || limit.is_none() {
                break;
            }
            // The cost bound admitted only rejected collapses: retry without it.
            bounded = false;
        } else {
            bounded = true;
        }
    }
    let capped = candidates.last().is_some_and(|c| c.key > cap);
    if state.live_faces <= target {
        StopReason::TargetReached
    } else if loop_state.rejected_for_error || capped {
        StopReason::MaxError
    } else {
        StopReason::NoValidCollapse
    }
}

/// What the collapse loop carries from batch to batch and pass to pass.
struct LoopState {
    /// Vertices changed (survivors) or removed in this pass.
    changed: VertexBits,
    /// Vertices changed in this batch, and the same as a list (to clear the bits).
    batch_changed: VertexBits,
    batch_list: Vec<u32>,
    /// The survivors of this pass, in collapse order (their edges are re-scored).
    touched: Vec<u32>,
    speculations: Speculations,
    check_scratch: CheckScratch,
    /// The collapses of a seam vertex's twins that go with the current one.
    twins: Vec<(u32, u32, Placement)>,
    /// Whether a collapse was refused for exceeding the error bound.
    rejected_for_error: bool,
}

impl LoopState {
    fn new(vertex_count: usize) -> Self {
        Self {
            changed: VertexBits::new(vertex_count),
            batch_changed: VertexBits::new(vertex_count),
            batch_list: Vec::new(),
            touched: Vec::new(),
            speculations: Speculations::default(),
            check_scratch: CheckScratch::default(),
            twins: Vec::new(),
            rejected_for_error: false,
        }
    }
}

/// Collapses the valid edges of `batch` in order (their placements and checks evaluated
/// speculatively in parallel first), until the mesh has `target` faces. `max_error2` bounds
/// the normalised cost.
fn collapse_batch(
    state: &mut Collapser,
    batch: &[Candidate],
    target: usize,
    max_error2: Option<f64>,
    loop_state: &mut LoopState,
) {
    let LoopState {
        changed,
        batch_changed,
        batch_list,
        touched,
        speculations,
        check_scratch,
        twins,
        rejected_for_error,
    } = loop_state;
    state.speculate(batch, changed, max_error2, speculations);
    for (&Candidate { a, b, .. }, spec) in batch.iter().zip(&speculations.results) {
        if state.live_faces <= target {
            break;
        }
        // Skips endpoints changed (or removed) earlier in this pass.
        if changed.contains(a) || changed.contains(b) {
            continue;
        }
        let allowed = match spec.verdict {
            Verdict::Skip => continue,
            Verdict::OverError => {
                *rejected_for_error = true;
                continue;
            }
            // A collapse earlier in the batch changed what the check read: redo it.
            _ if spec.touches(batch_changed) => {
                state.collapse_allowed(a, b, spec.placement.position, check_scratch)
            }
            verdict => verdict == Verdict::Allowed,
        };
        if !allowed {
            continue;
        }
        let survivor = spec.placement.survivor;
        let removed = if survivor == a { b } else { a };
        // A seam vertex goes only with its twin on the other side of the seam.
        twins.clear();
        if state.verts[removed as usize].locked()
            && (!state.twin_collapses(removed, survivor, check_scratch, twins)
                || twins
                    .iter()
                    .any(|&(r, s, p)| state.exceeds_error(r, s, p.cost, max_error2)))
        {
            continue;
        }
        twins.push((a, b, spec.placement));
        for &(a, b, placement) in twins.iter().rev() {
            let survivor = placement.survivor;
            let removed = if survivor == a { b } else { a };
            state.collapse(a, b, placement);
            // Done for this pass; the survivor and the neighbours whose flags changed are
            // re-scored for the next.
            let mut mark = |v: u32, rescore: bool| {
                if !changed.contains(v) {
                    if rescore {
                        touched.push(v);
                    }
                    changed.insert(v);
                    batch_changed.insert(v);
                    batch_list.push(v);
                }
            };
            mark(survivor, true);
            mark(removed, false);
            for &v in state.refreshed() {
                mark(v, true);
            }
        }
    }
    for v in batch_list.drain(..) {
        batch_changed.remove(v);
    }
}

/// The collapsible edges of `edges` (chunks, in order) with their cost keys, scored in
/// parallel (the far endpoints' records and quadrics warmed per 64 edges), sorted by key (ties
/// in the order of `edges`). Each chunk of edges is freed once scored, and all of them before
/// the sort: the first sort is the decimation's memory peak.
fn score(state: &Collapser, edges: Vec<Vec<(u32, u32)>>) -> Vec<Candidate> {
    let scored: Vec<Vec<Candidate>> = edges
        .into_par_iter()
        .map(|chunk| {
            let mut out = Vec::with_capacity(chunk.len());
            for group in chunk.chunks(64) {
                state.warm_records(group.iter().map(|&(_, b)| b));
                out.extend(group.iter().filter_map(|&(a, b)| {
                    state.placement(a, b).map(|p| Candidate {
                        key: cost_key(p.cost),
                        a,
                        b,
                    })
                }));
            }
            out
        })
        .collect();
    let mut candidates = Vec::with_capacity(scored.iter().map(Vec::len).sum());
    for chunk in scored {
        candidates.extend_from_slice(&chunk);
    }
    radix_sort(&mut candidates);
    candidates
}

/// The next pass's candidates: the previous ones with no endpoint in `changed` (the
/// survivors and removed vertices of the last pass; the others' costs are unchanged), merged
/// with the re-scored edges around the survivors `touched` in that pass.
fn rescore(
    state: &Collapser,
    previous: Vec<Candidate>,
    touched: &[u32],
    changed: &VertexBits,
) -> Vec<Candidate> {
    // Edges around touched survivors (alive: a changed vertex is not collapsed again in its
    // pass); one between two touched vertices is emitted by the smaller. Rings are small:
    // duplicates go by a local sort. The survivors are visited in vertex order, not in
    // collapse order: neighbouring survivors share faces, neighbours and quadrics, so the
    // gather streams through memory instead of missing the cache at every survivor. Each
    // chunk keeps one scratch ring and records where each survivor's edges went.
    let mut order: Vec<(u32, u32)> = touched
        .iter()
        .enumerate()
        .map(|(i, &s)| (s, i as u32))
        .collect();
    order.par_sort_unstable();
    // Per chunk: the scored edges and each survivor's `(start, len)` among them.
    type ScoredChunk = (Vec<Candidate>, Vec<(u32, u32)>);
    let chunks: Vec<ScoredChunk> = order
        .par_chunks(RESCORE_CHUNK)
        .map(|chunk| {
            let mut ring: Vec<u32> = Vec::new();
            let mut out: Vec<Candidate> = Vec::with_capacity(6 * chunk.len());
            let mut spans = Vec::with_capacity(chunk.len());
            let survivors: Vec<u32> = chunk.iter().map(|&(s, _)| s).collect();
            for (i, &s) in survivors.iter().enumerate() {
                if i % RESCORE_WARM == 0 {
                    let end = survivors.len().min(i + RESCORE_WARM);
                    state.warm(&survivors[i..end], true);
                }
                ring.clear();
                for k in state.incident(s) {
                    let face = state.faces[state.refs[k] as usize];
                    if face[0] == DEAD {
                        continue;
                    }
                    for v in face {
                        if v != s && (!changed.contains(v) || s < v) {
                            ring.push(v);
                        }
                    }
                }
                ring.sort_unstable();
                ring.dedup();
                let start = out.len() as u32;
                out.extend(ring.iter().filter_map(|&v| {
                    let (a, b) = (s.min(v), s.max(v));
                    state.placement(a, b).map(|p| Candidate {
                        key: cost_key(p.cost),
                        a,
                        b,
                    })
                }));
                spans.push((start, out.len() as u32 - start));
            }
            (out, spans)
        })
        .collect();
    // Back to collapse order (which fixes the order of equal keys, as before), then by key.
    let mut by_collapse = vec![(0u32, 0u32, 0u32); touched.len()];
    for (c, (_, spans)) in chunks.iter().enumerate() {
        let first = c * RESCORE_CHUNK;
        for (k, &(start, len)) in spans.iter().enumerate() {
            if let Some(&(_, i)) = order.get(first + k)
                && let Some(slot) = by_collapse.get_mut(i as usize)
            {
                *slot = (c as u32, start, len);
            }
        }
    }
    let mut fresh = Vec::with_capacity(chunks.iter().map(|(out, _)| out.len()).sum());
    for &(c, start, len) in &by_collapse {
        if let Some(edges) = chunks
            .get(c as usize)
            .and_then(|(out, _)| out.get(start as usize..(start + len) as usize))
        {
            fresh.extend_from_slice(edges);
        }
    }
    drop(chunks);
    radix_sort(&mut fresh);
    merge_sorted(
        &previous,
        |c| !changed.contains(c.a) && !changed.contains(c.b),
        &fresh,
    )
}
