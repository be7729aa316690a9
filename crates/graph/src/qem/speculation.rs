//! Speculative, parallel evaluation of the next collapses of a QEM pass (Garland & Heckbert,
//! SIGGRAPH 1997; thesis ch. 2.3.2): the collapse loop is sequential, but most of its time is
//! the placement and the validity checks of each candidate, which only *read* the mesh. A
//! batch of upcoming candidates is evaluated in parallel against the mesh as it is before the
//! batch; the sequential loop then reuses each verdict unless a collapse earlier in the batch
//! changed a vertex the evaluation read (its endpoints or their neighbours, the *footprint*),
//! in which case it re-runs the check. The result is therefore exactly that of the
//! sequential loop, for any thread count.

use rayon::prelude::*;

use super::candidates::Candidate;
use super::collapse_checks::CheckScratch;
use super::collapser::{Collapser, Placement};
use super::vertex_bits::VertexBits;

/// Footprints longer than this are not stored: such a verdict is always re-checked. 22
/// neighbours (valence up to ~12 at both ends) keep a [`Speculation`] at 128 bytes, two cache
/// lines; on the 1.3M-face benchmark no footprint exceeds 14 (30 before: 160 bytes).
const FOOTPRINT: usize = 22;

/// What the evaluation of one candidate found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Verdict {
    /// An endpoint changed earlier in the pass, or the edge has no placement: skip.
    Skip,
    /// The normalised cost exceeds the error bound.
    OverError,
    /// The checks reject the collapse.
    Rejected,
    /// The collapse is valid.
    Allowed,
}

/// The speculative result for one candidate (of a [`Verdict::Skip`], only the verdict is
/// meaningful).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Speculation {
    pub verdict: Verdict,
    pub placement: Placement,
    /// Number of valid entries of `footprint`; `u8::MAX` when it overflowed.
    len: u8,
    footprint: [u32; FOOTPRINT],
}

impl Speculation {
    fn skip(placement: Placement) -> Self {
        Self {
            verdict: Verdict::Skip,
            placement,
            len: 0,
            footprint: [0; FOOTPRINT],
        }
    }

    /// Whether the verdict may be stale: a vertex of the footprint is in `changed` (or the
    /// footprint was too long to store).
    pub(crate) fn touches(&self, changed: &VertexBits) -> bool {
        match self.footprint.get(..usize::from(self.len)) {
            Some(used) => used.iter().any(|&v| changed.contains(v)),
            None => true,
        }
    }
}

/// The reusable result buffer of [`Collapser::speculate`].
#[derive(Debug, Default)]
pub(crate) struct Speculations {
    /// The results, in the batch's order.
    pub results: Vec<Speculation>,
}

/// Candidates whose memory is warmed together (`Collapser::warm`) before they are evaluated.
const WARM_CHUNK: usize = 64;

impl Collapser {
    /// Evaluates `batch` in parallel into `buffers.results` (same order): placement, error
    /// bound and validity checks of each candidate whose endpoints are not in `changed`,
    /// against the current mesh. `max_error2` bounds the normalised cost (length², see
    /// `Decimation`).
    pub(crate) fn speculate(
        &self,
        batch: &[Candidate],
        changed: &VertexBits,
        max_error2: Option<f64>,
        buffers: &mut Speculations,
    ) {
        let nothing = Placement {
            cost: 0.0,
            position: [0.0; 3],
            survivor: 0,
            t: 0.0,
        };
        let evaluate = |scratch: &mut CheckScratch, &Candidate { a, b, .. }: &Candidate| {
            let Some(placement) = self.placement(a, b) else {
                return Speculation::skip(nothing);
            };
            if self.exceeds_error(a, b, placement.cost, max_error2) {
                return Speculation {
                    verdict: Verdict::OverError,
                    ..Speculation::skip(placement)
                };
            }
            let allowed = self.collapse_allowed(a, b, placement.position, scratch);
            let mut spec = Speculation {
                verdict: if allowed {
                    Verdict::Allowed
                } else {
                    Verdict::Rejected
                },
                ..Speculation::skip(placement)
            };
            for (k, v) in scratch.footprint().enumerate() {
                match spec.footprint.get_mut(k) {
                    Some(slot) => {
                        *slot = v;
                        spec.len += 1;
                    }
                    None => {
                        spec.len = u8::MAX;
                        break;
                    }
                }
            }
            spec
        };
        // Written in place: each parallel task fills its own slice of the reused buffer (no
        // per-task vectors to allocate and copy).
        buffers
            .results
            .resize(batch.len(), Speculation::skip(nothing));
        buffers
            .results
            .par_chunks_mut(WARM_CHUNK)
            .zip(batch.par_chunks(WARM_CHUNK))
            .for_each_init(
                || (CheckScratch::default(), Vec::new()),
                |(scratch, ends), (out, chunk)| {
                    ends.clear();
                    for c in chunk {
                        if !changed.contains(c.a) && !changed.contains(c.b) {
                            ends.extend([c.a, c.b]);
                        }
                    }
                    self.warm(ends, false);
                    for (slot, c) in out.iter_mut().zip(chunk) {
                        if changed.contains(c.a) || changed.contains(c.b) {
                            // Most of a pass's candidates: only the verdict is written (the
                            // loop reads nothing else of a skipped candidate), which halves
                            // the memory written for them.
                            slot.verdict = Verdict::Skip;
                        } else {
                            *slot = evaluate(scratch, c);
                        }
                    }
                },
            );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::qem::decimation::DecimationOptions;
    use meshgnn_geometry::{TriMesh, icosphere};

    /// An icosphere with deterministic radial noise (so some collapses are rejected).
    fn noisy_sphere(subdivisions: u32, amp: f32) -> TriMesh {
        let sphere = icosphere(subdivisions);
        let vertices = sphere
            .vertices()
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let h = ((i as f32 * 12.9898).sin() * 43758.547).fract();
                p.map(|x| x * (1.0 + amp * h))
            })
            .collect();
        sphere.with_vertices(vertices).unwrap()
    }

    /// The collapser of a noisy sphere and every initial edge as a candidate batch.
    fn noisy_sphere_with_every_edge() -> (Collapser, Vec<Candidate>) {
        let mesh = noisy_sphere(3, 0.08);
        let mut state = Collapser::new(&mesh, &DecimationOptions::default(), &[], None).unwrap();
        let batch = std::mem::take(&mut state.initial_edges)
            .into_iter()
            .flatten()
            .map(|(a, b)| Candidate { key: 0, a, b })
            .collect();
        (state, batch)
    }

    #[test]
    fn reused_buffer_skips_changed_endpoints_and_matches_fresh_checks() {
        let (state, batch) = noisy_sphere_with_every_edge();
        let n = state.verts.len();
        let mut specs = Speculations::default();
        // Fill the buffer with a larger batch first: its stale entries must not leak.
        state.speculate(&batch, &VertexBits::new(n), None, &mut specs);
        let mut changed = VertexBits::new(n);
        for v in (0..n as u32).step_by(7) {
            changed.insert(v);
        }
        let half = &batch[..batch.len() / 2];
        state.speculate(half, &changed, None, &mut specs);
        assert_eq!(specs.results.len(), half.len());
        let mut scratch = CheckScratch::default();
        let (mut skipped, mut evaluated) = (0, 0);
        for (c, spec) in half.iter().zip(&specs.results) {
            if changed.contains(c.a) || changed.contains(c.b) {
                assert_eq!(spec.verdict, Verdict::Skip, "{c:?}");
                skipped += 1;
            } else {
                let p = state.placement(c.a, c.b).unwrap();
                assert_eq!(spec.placement.position, p.position);
                assert_eq!(spec.placement.cost, p.cost);
                let allowed = state.collapse_allowed(c.a, c.b, p.position, &mut scratch);
                assert_eq!(spec.verdict == Verdict::Allowed, allowed, "{c:?}");
                assert!(!spec.touches(&VertexBits::new(n)));
                evaluated += 1;
            }
        }
        assert!(skipped > 100 && evaluated > 100, "{skipped} {evaluated}");
    }

    #[test]
    fn verdicts_match_fresh_checks_unless_their_footprint_changed() {
        let (mut state, batch) = noisy_sphere_with_every_edge();
        let n = state.verts.len();
        let mut specs = Speculations::default();
        state.speculate(&batch, &VertexBits::new(n), None, &mut specs);
        assert_eq!(specs.results.len(), batch.len());
        let mut scratch = CheckScratch::default();
        let fresh = |state: &Collapser, c: &Candidate, scratch: &mut CheckScratch| {
            let p = state.placement(c.a, c.b).unwrap();
            (
                p.position,
                state.collapse_allowed(c.a, c.b, p.position, scratch),
            )
        };
        // Before any collapse, the parallel evaluation is the sequential one.
        for (c, spec) in batch.iter().zip(&specs.results) {
            let (position, allowed) = fresh(&state, c, &mut scratch);
            assert_eq!(spec.placement.position, position);
            assert_eq!(spec.verdict == Verdict::Allowed, allowed, "{c:?}");
        }
        // Collapse a sparse spread of edges (each vertex at most once, as in a pass).
        let mut changed = VertexBits::new(n);
        let mut collapses = 0;
        for c in batch.iter().step_by(31) {
            if changed.contains(c.a) || changed.contains(c.b) {
                continue;
            }
            let p = state.placement(c.a, c.b).unwrap();
            if state.collapse_allowed(c.a, c.b, p.position, &mut scratch) {
                state.collapse(c.a, c.b, p);
                changed.insert(c.a);
                changed.insert(c.b);
                collapses += 1;
            }
        }
        // A verdict whose endpoints and footprint are untouched is still exact; the touched
        // ones include verdicts that really changed (the footprint is not idle).
        let (mut reused, mut turned) = (0, 0);
        for (c, spec) in batch.iter().zip(&specs.results) {
            if changed.contains(c.a) || changed.contains(c.b) {
                continue;
            }
            let (position, allowed) = fresh(&state, c, &mut scratch);
            assert_eq!(spec.placement.position, position);
            if spec.touches(&changed) {
                turned += usize::from((spec.verdict == Verdict::Allowed) != allowed);
            } else {
                assert_eq!(spec.verdict == Verdict::Allowed, allowed, "{c:?}");
                reused += 1;
            }
        }
        assert!(collapses > 40 && reused > 300, "{collapses} {reused}");
        assert!(turned > 0, "{collapses} {reused} {turned}");
    }
}
