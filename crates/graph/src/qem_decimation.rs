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
//! 4. Edges are collapsed cheapest first, in passes (as meshoptimizer does): the first pass
//!    scores every edge in parallel and radix-sorts them by cost (ties in a fixed order); it
//!    collapses in that order up to the cost `1.5 ×` that of the edge ranked
//!    `(#F − target) / 2`, skipping edges whose endpoint was already changed in this pass (a
//!    per-vertex pass stamp: lazy invalidation, since only those edges' costs went stale).
//!    The next pass keeps the still-valid sorted candidates and merges in the re-scored edges
//!    around the changed vertices. A collapse is rejected when it would break the link
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
//! # Guarantees
//! - From an edge-manifold, consistently oriented input: no flipped face, no new hole, no
//!   non-manifold edge; a watertight input stays watertight. Every output face stays within
//!   ~78° of the input surface around its corners (a noisy sphere whose input faces all point
//!   outwards decimates to one whose faces all point outwards).
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

use meshgnn_geometry::TriMesh;
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::qem_candidates::{Candidate, cost_key, key_cost, merge_sorted, radix_sort};
use crate::qem_collapser::{Collapser, DEAD};

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
    let stop_reason = run(&mut state, target, options, progress);
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

/// The collapse passes over `state`; returns why they stopped.
fn run(
    state: &mut Collapser,
    target: usize,
    options: &DecimationOptions,
    progress: &mut dyn FnMut(f64),
) -> StopReason {
    let max_error2 = options.max_error.map(|e| e * e);
    let initial = state.live_faces;
    let to_remove = initial.saturating_sub(target).max(1) as f64;
    let mut rejected_for_error = false;
    let mut bounded = true;
    let mut pass = 0u32;
    let mut scratch = Vec::new();
    let initial_edges = std::mem::take(&mut state.initial_edges);
    let mut candidates = score(state, &initial_edges, &mut scratch);
    drop(initial_edges);
    let mut touched: Vec<u32> = Vec::new();
    let mut removed: Vec<u32> = Vec::new();
    while state.live_faces > target {
        pass += 1;
        if pass > 1 {
            candidates = rescore(
                state,
                candidates,
                &touched,
                &removed,
                pass - 1,
                &mut scratch,
            );
        }
        touched.clear();
        removed.clear();
        let goal = (state.live_faces - target).div_ceil(2);
        let limit = match candidates.get(goal) {
            Some(c) if bounded => Some(cost_key(PASS_COST_SLACK * key_cost(c.key))),
            _ => None,
        };
        let collapses_before = state.collapses;
        for &Candidate { key, a, b } in &candidates {
            if state.live_faces <= target || limit.is_some_and(|l| key > l) {
                break;
            }
            // Skips dead endpoints (stamp DEAD) and those changed in this pass.
            let (sa, sb) = (state.verts[a as usize].stamp, state.verts[b as usize].stamp);
            if sa == pass || sb == pass || sa == DEAD || sb == DEAD {
                continue;
            }
            // Untouched endpoints: the placement is the one scored above.
            let Some(placement) = state.placement(a, b) else {
                continue;
            };
            if let Some(limit) = max_error2 {
                let weight = (state.quadrics[a as usize] + state.quadrics[b as usize]).weight();
                if weight > 0.0 && placement.cost / weight > limit {
                    rejected_for_error = true;
                    continue;
                }
            }
            if !state.collapse_allowed(a, b, placement.position) {
                continue;
            }
            state.collapse(a, b, placement, pass);
            touched.push(placement.survivor);
            removed.push(if placement.survivor == a { b } else { a });
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
    if state.live_faces <= target {
        StopReason::TargetReached
    } else if rejected_for_error {
        StopReason::MaxError
    } else {
        StopReason::NoValidCollapse
    }
}

/// The collapsible edges of `edges` with their cost keys, scored in parallel, sorted by key
/// (ties in the order of `edges`).
fn score(state: &Collapser, edges: &[(u32, u32)], scratch: &mut Vec<Candidate>) -> Vec<Candidate> {
    let mut candidates: Vec<Candidate> = edges
        .par_iter()
        .filter_map(|&(a, b)| {
            state.placement(a, b).map(|p| Candidate {
                key: cost_key(p.cost),
                a,
                b,
            })
        })
        .collect();
    radix_sort(&mut candidates, scratch);
    candidates
}

/// The next pass's candidates: the previous ones whose endpoints were neither `touched`
/// (survivors) nor `removed` in pass `pass` (their cost is unchanged), merged with the
/// re-scored edges around the vertices `touched` in that pass.
fn rescore(
    state: &Collapser,
    previous: Vec<Candidate>,
    touched: &[u32],
    removed: &[u32],
    pass: u32,
    scratch: &mut Vec<Candidate>,
) -> Vec<Candidate> {
    // One bit per vertex (cache resident, unlike the vertex records): changed or removed.
    let mut stale = vec![0u64; state.verts.len().div_ceil(64)];
    for &v in touched.iter().chain(removed) {
        stale[v as usize / 64] |= 1 << (v % 64);
    }
    let valid = |v: u32| stale[v as usize / 64] & (1 << (v % 64)) == 0;
    // Order-preserving parallel filter.
    let kept: Vec<Candidate> = previous
        .into_par_iter()
        .filter(|c| valid(c.a) && valid(c.b))
        .collect();
    // Edges around touched survivors; one between two touched vertices is emitted by the
    // smaller. A survivor's ring is small, so duplicates are removed by a local scan.
    let fresh_edges: Vec<(u32, u32)> = touched
        .par_iter()
        .flat_map_iter(|&s| {
            let mut ring: Vec<u32> = Vec::new();
            if state.verts[s as usize].alive() {
                for k in state.incident(s) {
                    let face = state.faces[state.refs[k] as usize];
                    if face[0] == DEAD {
                        continue;
                    }
                    for v in face {
                        if v != s && (state.verts[v as usize].stamp != pass || s < v) {
                            ring.push(v);
                        }
                    }
                }
            }
            ring.sort_unstable();
            ring.dedup();
            ring.into_iter().map(move |v| (s.min(v), s.max(v)))
        })
        .collect();
    let fresh = score(state, &fresh_edges, scratch);
    merge_sorted(&kept, &fresh)
}
