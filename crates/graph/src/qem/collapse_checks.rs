//! Whether one QEM edge collapse keeps the mesh valid: the link condition (Dey et al., "Topology
//! preserving edge contraction", 1999) so a 2-manifold stays one, and the geometric checks of
//! Garland & Heckbert (SIGGRAPH 1997, §3: "mesh inversion") against flipped, folded and
//! degenerate faces. Thesis ch. 2.3.2.

use std::cmp::Ordering;

use super::collapser::{Collapser, DEAD, Placement};
use super::weld_by_position::twins_of;
use meshgnn_geometry::vec3::{cross, dot, sub};

/// Normals of faces may turn by at most `acos(0.2)` ≈ 78° in one collapse.
pub(crate) const MIN_NORMAL_COS: f64 = 0.2;
/// A moved face must stay within `acos(0.2)` ≈ 78° of the input surface its corners stand for
/// (the sum of their region normals). A face already beyond that bound may stay beyond it if
/// it does not turn its back on that surface, or turns towards it: scans hold faces folded
/// against their corners' surface (2 % of snowden.obj's), thin parts hold faces edge-on to it
/// (a thin plate's rim), and a bound they never met would freeze every collapse around them.
pub(crate) const MIN_REGION_COS: f64 = 0.2;
/// The corners' summed region normal is that reference only where they agree, with
/// `|Σ r| ≥ 0.8 · Σ |r|`: across a thin part (a plate, a wire, the glasses of snowden.obj at
/// 1 %) the corners stand for opposite sides, and their sum says nothing about which way a
/// face between them should point (0.9 let a noisy sphere's face turn inwards).
const MIN_CORNER_AGREEMENT: f64 = 0.8;
/// A face whose doubled area is below this fraction of its longest squared edge is degenerate.
const MIN_SLIVER: f64 = 1e-7;

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

/// Whether the region normals `corners` of a face's corners point different ways (their sum
/// `region` is short of [`MIN_CORNER_AGREEMENT`] times their lengths' sum; false for NaN).
fn corners_disagree(region: [f64; 3], corners: [[f32; 3]; 3]) -> bool {
    let length = |r: [f64; 3]| dot(r, r).sqrt();
    let lengths: f64 = corners.iter().map(|r| length(r.map(f64::from))).sum();
    length(region) < MIN_CORNER_AGREEMENT * lengths
}

/// Number of values of `x` also in `y` (both free of duplicates, small).
fn common_count(x: &[u32], y: &[u32]) -> usize {
    x.iter().filter(|v| y.contains(v)).count()
}

/// The link condition where `a` or `b` lies on a non-manifold edge, stated on face counts
/// (`fan_a`, `ring_a`: the faces and neighbours of `a`, without `b`; likewise for `b`):
/// every common neighbour `x` is the apex of a face on `(a, b)`, and the edge `(x, survivor)`
/// that `(a, x)` and `(b, x)` merge into ends with at most `max(2, n_ax, n_bx)` faces
/// (`n_ax + n_bx − 2·n_abx`), so no edge becomes non-manifold and none becomes more so.
fn edge_face_counts_kept(
    b: u32,
    fan_a: &[[u32; 3]],
    fan_b: &[[u32; 3]],
    ring_a: &[u32],
    ring_b: &[u32],
) -> bool {
    ring_a.iter().filter(|x| ring_b.contains(x)).all(|&x| {
        let count = |fan: &[[u32; 3]]| fan.iter().filter(|f| f.contains(&x)).count();
        let (n_ax, n_bx) = (count(fan_a), count(fan_b));
        let n_abx = fan_a
            .iter()
            .filter(|f| f.contains(&x) && f.contains(&b))
            .count();
        n_abx > 0 && n_ax + n_bx - 2 * n_abx <= n_ax.max(n_bx).max(2)
    })
}

/// Reusable buffers of [`Collapser::collapse_allowed`] (one per thread), holding after a call
/// the neighbours the check read: its *footprint*.
#[derive(Debug, Default)]
pub(crate) struct CheckScratch {
    fan_a: Vec<[u32; 3]>,
    fan_b: Vec<[u32; 3]>,
    ring_a: Vec<u32>,
    ring_b: Vec<u32>,
    pairs: Vec<[u32; 2]>,
}

impl CheckScratch {
    /// The neighbours of `a` and `b` read by the last check (besides `a` and `b`; the apexes of
    /// the shared faces appear twice). The check's answer can only change when one of these or
    /// an endpoint changes.
    pub(crate) fn footprint(&self) -> impl Iterator<Item = u32> + '_ {
        self.ring_a.iter().chain(&self.ring_b).copied()
    }
}

impl Collapser {
    /// Collects the live faces around `v` into `fan` and its neighbours other than `skip`
    /// (each once) into `ring`.
    fn gather(&self, v: u32, skip: u32, fan: &mut Vec<[u32; 3]>, ring: &mut Vec<u32>) {
        fan.clear();
        ring.clear();
        for k in self.incident(v) {
            let face = self.faces[self.refs[k] as usize];
            if face[0] == DEAD {
                continue;
            }
            fan.push(face);
            for x in face {
                // Rings are small (~6): a linear scan beats sorting.
                if x != v && x != skip && !ring.contains(&x) {
                    ring.push(x);
                }
            }
        }
    }

    /// Link condition, boundary, duplicate-face, flip, fold and degeneracy checks for
    /// collapsing `(a, b)` to `p` (both fans move: the placement need not be an endpoint).
    ///
    /// Rejected when: the common neighbours of `a` and `b` are not exactly the apexes of their
    /// shared faces (the link condition: a pinched vertex or edge would appear); an interior
    /// edge joins two boundary vertices (it would pinch the boundary); around a non-manifold
    /// vertex, an edge would end with more faces than it and its merged twin had (or than 2),
    /// or two such vertices would merge other than along a non-manifold edge; the two fans hold
    /// opposite edges `(x, y)` (duplicate faces); `a` and `b` are all their component has
    /// left; or a moved face turns by more than `acos(MIN_NORMAL_COS)`, leaves the input
    /// surface its corners stand for by more than `acos(MIN_REGION_COS)`, or degenerates.
    /// Reads only `a`, `b`, their fans and their neighbours (`scratch.footprint()` afterwards).
    pub(crate) fn collapse_allowed(
        &self,
        a: u32,
        b: u32,
        p: [f32; 3],
        scratch: &mut CheckScratch,
    ) -> bool {
        let CheckScratch {
            fan_a,
            fan_b,
            ring_a,
            ring_b,
            pairs,
        } = scratch;
        self.gather(a, b, fan_a, ring_a);
        self.gather(b, a, fan_b, ring_b);
        self.fans_allow(a, b, p, fan_a, fan_b, ring_a, ring_b, pairs)
    }

    #[allow(clippy::too_many_arguments)]
    fn fans_allow(
        &self,
        a: u32,
        b: u32,
        p: [f32; 3],
        fan_a: &[[u32; 3]],
        fan_b: &[[u32; 3]],
        ring_a: &[u32],
        ring_b: &[u32],
        pairs: &mut Vec<[u32; 2]>,
    ) -> bool {
        let shared = fan_b.iter().filter(|f| f.contains(&a)).count();
        let (va, vb) = (self.verts[a as usize], self.verts[b as usize]);
        if shared == 0 || fan_a.len() + fan_b.len() == 2 * shared {
            return false;
        }
        if va.non_manifold() || vb.non_manifold() {
            if !edge_face_counts_kept(b, fan_a, fan_b, ring_a, ring_b)
                || (va.non_manifold() && vb.non_manifold() && shared < 3)
            {
                return false;
            }
        } else if shared > 2 || common_count(ring_a, ring_b) != shared {
            return false;
        }
        if shared == 2 && va.boundary() && vb.boundary() {
            return false;
        }
        // Duplicate faces: an opposite edge present around both a and b.
        pairs.clear();
        for &face in fan_a.iter().filter(|f| !f.contains(&b)) {
            let [x, y] = others(face, a);
            pairs.push([x.min(y), x.max(y)]);
        }
        for &face in fan_b.iter().filter(|f| !f.contains(&a)) {
            let [x, y] = others(face, b);
            if pairs.contains(&[x.min(y), x.max(y)]) {
                return false;
            }
        }
        // Flips, folds and degenerate faces around both ends.
        let (ra, rb) = (va.region_normal, vb.region_normal);
        let merged_region: [f32; 3] = std::array::from_fn(|k| ra[k] + rb[k]);
        let p = p.map(f64::from);
        for (moving, other, fan) in [(a, b, fan_a), (b, a, fan_b)] {
            for &face in fan.iter().filter(|f| !f.contains(&other)) {
                let [x, y] = others(face, moving);
                let (vx, vy) = (self.verts[x as usize], self.verts[y as usize]);
                let (px, py) = (vx.point(), vy.point());
                let old = self.verts[moving as usize].point();
                // The face is (moving, x, y) in winding order.
                let n_old = cross(sub(px, old), sub(py, old));
                let (ex, ey) = (sub(px, p), sub(py, p));
                let n_new = cross(ex, ey);
                let len_new2 = dot(n_new, n_new);
                let exy = sub(py, px);
                let longest2 = dot(ex, ex).max(dot(ey, ey)).max(dot(exy, exy));
                // Also rejects NaN (written so that a NaN compares as degenerate).
                if len_new2.sqrt().partial_cmp(&(MIN_SLIVER * longest2)) != Some(Ordering::Greater)
                {
                    return false;
                }
                let len_old2 = dot(n_old, n_old);
                if len_old2 > 0.0
                    && dot(n_old, n_new) < MIN_NORMAL_COS * (len_old2 * len_new2).sqrt()
                {
                    return false;
                }
                // Nor may it fold away from the input surface its corners represent.
                let around = |r: [f32; 3]| -> [f64; 3] {
                    std::array::from_fn(|k| {
                        f64::from(r[k]) + f64::from(vx.region_normal[k] + vy.region_normal[k])
                    })
                };
                let region = around(merged_region);
                let norms = (dot(region, region) * len_new2).sqrt();
                if dot(region, n_new) < MIN_REGION_COS * norms
                    && !corners_disagree(
                        region,
                        [merged_region, vx.region_normal, vy.region_normal],
                    )
                {
                    let cos_new = dot(region, n_new) / norms;
                    let region_old = around(self.verts[moving as usize].region_normal);
                    let cos_old =
                        dot(region_old, n_old) / (dot(region_old, region_old) * len_old2).sqrt();
                    // Also rejects NaN.
                    let stays_facing = cos_old < MIN_REGION_COS && cos_new >= 0.0;
                    if !(cos_new > cos_old || stays_facing) {
                        return false;
                    }
                }
            }
        }
        true
    }

    /// The collapses that go with removing seam vertex `removed` into `survivor` along a
    /// seam edge, written to `out`: each twin of `removed` (same position, another UV chart)
    /// into a twin of `survivor` along a seam edge of its chart, placed at that twin and
    /// checked like any collapse. False, and then none of them happens, when a twin of
    /// `removed` finds no such edge, the pairs' fans touch one another, or a check rejects.
    pub(crate) fn twin_collapses(
        &self,
        removed: u32,
        survivor: u32,
        scratch: &mut CheckScratch,
        out: &mut Vec<(u32, u32, Placement)>,
    ) -> bool {
        out.clear();
        let fan_touches = |v: u32, others: &[u32]| {
            self.refs[self.incident(v)].iter().any(|&f| {
                let face = self.faces[f as usize];
                face[0] != DEAD && others.iter().any(|o| face.contains(o))
            })
        };
        let mut moved = vec![removed, survivor];
        for r in twins_of(&self.twin, removed) {
            let Some(s) = twins_of(&self.twin, survivor)
                .find(|&s| !moved.contains(&s) && self.edge_face_count(r, s) == 1)
            else {
                return false;
            };
            let position = self.verts[s as usize].position;
            if fan_touches(r, &moved)
                || fan_touches(s, &moved)
                || !self.collapse_allowed(r, s, position, scratch)
            {
                return false;
            }
            let cost = (self.quadrics[r as usize] + self.quadrics[s as usize])
                .evaluate(position.map(f64::from));
            out.push((
                r,
                s,
                Placement {
                    cost,
                    position,
                    survivor: s,
                    t: 1.0,
                },
            ));
            moved.extend([r, s]);
        }
        true
    }
}
