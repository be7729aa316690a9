//! The cost and position of one QEM edge collapse (Garland & Heckbert, SIGGRAPH 1997, §4:
//! "optimal placement" by solving `A v = −b`, falling back to the endpoints and the midpoint
//! when `A` is singular). Thesis ch. 2.3.2.

use super::collapser::{Collapser, Placement};
use meshgnn_geometry::vec3::{dot, sub};

impl Collapser {
    /// Eq. (GH97 §4): the cheapest placement of collapsing edge `(a, b)` under
    /// `Q_a + Q_b`; `None` when both ends are locked and `(a, b)` is not a seam edge (one
    /// face), or both are pinned (locked or on a non-manifold edge) and `(a, b)` is not itself
    /// a non-manifold edge.
    ///
    /// A kept vertex stays where it is: an edge to one collapses onto it, and an edge between
    /// two is never collapsed. Boundaries stay on the input's boundary polyline: an interior →
    /// boundary edge collapses onto the boundary vertex and a boundary edge to the best point
    /// of its segment.
    /// Non-manifold edges keep their vertices: an edge to a pinned vertex collapses onto it,
    /// and one along a non-manifold edge or a seam onto one of its ends. An edge whose ends
    /// must both stay by these rules (a kept vertex beside a border or pinned one) is never
    /// collapsed. Every
    /// candidate position is rounded to `f32` (the output precision) before it is scored, so
    /// the cost and the validity checks see exactly the position that is written.
    pub(crate) fn placement(&self, a: u32, b: u32) -> Option<Placement> {
        let (ia, ib) = (a as usize, b as usize);
        let (va, vb) = (self.verts[ia], self.verts[ib]);
        let (ka, kb) = (va.kept(), vb.kept());
        let (la, lb) = (va.locked(), vb.locked());
        let (pin_a, pin_b) = (la || va.non_manifold(), lb || vb.non_manifold());
        if la && lb {
            if self.edge_face_count(a, b) != 1 {
                return None;
            }
        } else if pin_a && pin_b && self.edge_face_count(a, b) < 3 {
            return None;
        }
        let q = self.quadrics[ia] + self.quadrics[ib];
        let (pa, pb) = (va.point(), vb.point());
        let mut best = Placement {
            cost: f64::INFINITY,
            position: va.position,
            survivor: a,
            t: 0.0,
        };
        let mut consider = |position: [f64; 3], survivor: u32, t: f64| {
            let rounded = position.map(|x| x as f32);
            let cost = q.evaluate(rounded.map(f64::from));
            if cost < best.cost {
                best = Placement {
                    cost,
                    position: rounded,
                    survivor,
                    t,
                };
            }
        };
        let (ba, bb) = (va.boundary(), vb.boundary());
        let a_stays = ka || (la && !lb) || (pin_a && !pin_b) || (ba && !bb && !pin_b);
        let b_stays = kb || (lb && !la) || (pin_b && !pin_a) || (bb && !ba && !pin_a);
        let at = |t: f64| std::array::from_fn(|i| pa[i] + t * (pb[i] - pa[i]));
        if a_stays && b_stays {
            return None;
        } else if a_stays {
            consider(pa, a, 0.0);
        } else if b_stays {
            consider(pb, b, 1.0);
        } else if self.keep_original_positions || (pin_a && pin_b) {
            consider(pa, a, 0.0);
            consider(pb, b, 1.0);
        } else if ba && bb {
            // Along a boundary edge: `Q(a + t·e)` is quadratic in `t`; fit it from 3 values.
            let (f0, fh, f1) = (q.evaluate(pa), q.evaluate(at(0.5)), q.evaluate(pb));
            let (lin, quad) = (4.0 * fh - 3.0 * f0 - f1, 2.0 * f1 - 4.0 * fh + 2.0 * f0);
            if quad > 0.0 {
                let t = (-lin / (2.0 * quad)).clamp(0.0, 1.0);
                consider(at(t), a, t);
            }
            consider(pa, a, 0.0);
            consider(pb, b, 1.0);
            consider(at(0.5), a, 0.5);
        } else if let Some(p) = q.optimal_point() {
            // The optimum of a positive definite quadric is its global minimum: no other
            // candidate can cost less (up to the f32 rounding of the position).
            let e = sub(pb, pa);
            let len2 = dot(e, e);
            let t = if len2 > 0.0 {
                (dot(sub(p, pa), e) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            consider(p, a, t);
        } else {
            consider(pa, a, 0.0);
            consider(pb, b, 1.0);
            consider(at(0.5), a, 0.5);
        }
        best.cost.is_finite().then_some(best)
    }
}
