//! The six 4DFAB expressions (happy, sad, surprise, angry, disgust, fear — thesis ch. 4.4.1)
//! as muscle-like deformations of a neutral face from [`crate::FaceTemplate`].
//!
//! Each expression combines a few actions, each acting on a smooth region of the face chart
//! and moving the skin the way the anatomy does, mostly by rotations and saturating or
//! buckling motions, so that the deformation is non-linear in the intensity — the
//! non-linearity that the ch. 4 generator must learn and a linear PCA blendshape model
//! (the Table 4.2 baseline) cannot represent exactly:
//!
//! - **jaw**: the lower face rotates about a horizontal axis near the ears;
//! - **lip corners**: rotation about the mouth's forward axis (curl up or down) and a pull
//!   backwards; **stretch**: the corners slide sideways around the head (a rotation about
//!   the vertical axis);
//! - **pucker**: the mouth narrows towards the midline and the compressed lips buckle
//!   forward (height `∝ √(k(2−k))` for compression `k`, like a compressed strip) and evert;
//! - **press**: the lips roll inwards about their roots and flatten, the chin pushes up;
//! - **upper-lip raise**: the upper lip lifts and everts about the nose base;
//! - **brows**: raise along the forehead (an arc about the head centre; forehead lines appear
//!   past a threshold), inner-brow raise, pinch; **furrow**: the brows drop (the inner ends
//!   most), are drawn together, and the compressed skin between them bunches forward with
//!   two vertical lines;
//! - **cheek raise**: the cheeks lift and bulge (quadratically), deepen the nasolabial folds,
//!   push the lower lids up and raise crow's feet past a threshold;
//! - **nose wrinkle**: the nose sides lift, the nostrils flare, transverse lines appear;
//! - **eyelids**: the upper lid rotates about the eyeball's centre down over the eye until it
//!   meets the lower lid (closure saturates just short of contact), or up to widen the eye;
//!   the lower lid rises with `lid` and the cheeks.
//!
//! A subject's [`ExpressionStyle`] adds gains, a left/right imbalance and its own wrinkle
//! pattern ([`apply_styled_actions`]); [`apply_actions`] is the default style.
//!
//! # Conventions
//! - Millimetres and degrees as documented per field; chart coordinates as in
//!   [`crate::FaceTemplate`]. Left is +x.
//! - Zero actions leave the face unchanged bit for bit.

use crate::expression_style::ExpressionStyle;
use crate::face_template::{
    EYE_HALF_WIDTH, EYE_X, EYE_Y, EYEBALL_RADIUS, FaceTemplate, MOUTH_HALF_WIDTH, gauss,
    lid_margins, nasolabial_fold, segment_distance, smoothstep,
};
use crate::vec3::{V3, add, axis_angle, mul_v, norm, normalize, scale, sub, to_f32, to_f64};

/// One of the six 4DFAB expressions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Expression {
    /// Smile: corners up, cheeks up, slight jaw opening, squint.
    Happy,
    /// Corners down, inner brows up.
    Sad,
    /// Jaw drop, brows up, eyes wide.
    Surprise,
    /// Brows down and pinched, lips pressed, corners down.
    Angry,
    /// Upper lip and nose wrinkled up, brows down.
    Disgust,
    /// Mouth stretched and open, inner brows up, eyes wide.
    Fear,
}

impl Expression {
    /// All six, in the label order used by the one-hot motion labels.
    pub const ALL: [Expression; 6] = [
        Expression::Happy,
        Expression::Sad,
        Expression::Surprise,
        Expression::Angry,
        Expression::Disgust,
        Expression::Fear,
    ];

    /// Lower-case name (`happy`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Expression::Happy => "happy",
            Expression::Sad => "sad",
            Expression::Surprise => "surprise",
            Expression::Angry => "angry",
            Expression::Disgust => "disgust",
            Expression::Fear => "fear",
        }
    }

    /// Position in [`Expression::ALL`] (the one-hot label index).
    pub fn index(self) -> usize {
        Expression::ALL.iter().position(|&e| e == self).unwrap_or(0)
    }

    /// The actions at full intensity (the textbook performance; a subject's
    /// [`ExpressionStyle`] varies them).
    pub fn actions(self) -> Actions {
        let z = Actions::default();
        match self {
            // Duchenne smile: corners up and back, cheeks up, eyes narrowed from below and
            // above.
            Expression::Happy => Actions {
                jaw_deg: 4.0,
                corner_deg: 18.0,
                corner_pull: 4.0,
                stretch: 2.0,
                cheek: 5.0,
                lid: 1.0,
                eye_close: 0.35,
                ..z
            },
            // Inner brows up and together, lids drooping, corners down, chin pushed up.
            Expression::Sad => Actions {
                jaw_deg: 1.5,
                corner_deg: -15.0,
                inner_brow: 5.0,
                brow: -1.0,
                furrow: 1.5,
                eye_close: 0.25,
                press: 1.0,
                ..z
            },
            // Jaw drop, brows up with forehead lines, eyes wide, lips slightly rounded.
            Expression::Surprise => Actions {
                jaw_deg: 11.0,
                brow: 8.0,
                inner_brow: 1.0,
                eye_close: -0.5,
                lid: -1.0,
                pucker: 0.15,
                ..z
            },
            // Brows down and together with bunched skin between them, tense lower lids,
            // lips pressed, corners down.
            Expression::Angry => Actions {
                furrow: 5.0,
                brow: -2.0,
                pinch: 0.04,
                press: 2.5,
                corner_deg: -4.0,
                lid: 1.8,
                nose: 1.0,
                ..z
            },
            // Nose wrinkled, upper lip raised, brows lowered, cheeks up, eyes narrowed.
            Expression::Disgust => Actions {
                jaw_deg: 3.0,
                upper_lip: 5.0,
                nose: 4.0,
                furrow: 2.5,
                brow: -1.0,
                corner_deg: -8.0,
                cheek: 2.5,
                lid: 1.5,
                eye_close: 0.25,
                ..z
            },
            // Mouth stretched and open, brows up and drawn together, eyes wide.
            Expression::Fear => Actions {
                jaw_deg: 7.0,
                stretch: 6.0,
                inner_brow: 5.0,
                brow: 4.0,
                furrow: 2.0,
                eye_close: -0.5,
                lid: 0.5,
                ..z
            },
        }
    }
}

/// Amplitudes of the facial actions (degrees, millimetres or fractions).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Actions {
    /// Jaw opening angle (degrees).
    pub jaw_deg: f64,
    /// Lip-corner rotation (degrees, positive up).
    pub corner_deg: f64,
    /// Lip-corner backward pull (mm).
    pub corner_pull: f64,
    /// Whole-brow raise along the forehead (mm, negative lowers).
    pub brow: f64,
    /// Inner-brow raise (mm).
    pub inner_brow: f64,
    /// Brow pinch towards the midline (fraction of x).
    pub pinch: f64,
    /// Cheek raise (mm).
    pub cheek: f64,
    /// Nose wrinkle (mm up).
    pub nose: f64,
    /// Upper-lip raise (mm).
    pub upper_lip: f64,
    /// Mouth stretch (mm sideways at the corners, around the head).
    pub stretch: f64,
    /// Lower-lid raise (mm; negative lowers it, widening the eyes).
    pub lid: f64,
    /// Lip pucker: 1 narrows the mouth by about 40 % and pushes the lips about 9 mm forward
    /// (saturating above 1).
    pub pucker: f64,
    /// Lip press (mm the lips are pushed back; they also roll inwards and the chin rises).
    pub press: f64,
    /// Brow furrow (mm the inner brows drop; the brows are drawn together and the skin
    /// between them bunches).
    pub furrow: f64,
    /// Upper-lid closure: fraction of the lid opening closed (1: the upper lid meets the
    /// lower one, saturating just short of contact; negative opens the eye wider, at most
    /// −0.45).
    pub eye_close: f64,
}

impl Actions {
    /// Every amplitude multiplied by `s` (a subject's style or an intensity).
    ///
    /// ```
    /// use meshgnn_data::{Actions, Expression};
    /// let a = Expression::Angry.actions().scaled(0.5);
    /// assert_eq!((a.furrow, a.press), (2.5, 1.25));
    /// ```
    pub fn scaled(self, s: f64) -> Self {
        Self {
            jaw_deg: self.jaw_deg * s,
            corner_deg: self.corner_deg * s,
            corner_pull: self.corner_pull * s,
            brow: self.brow * s,
            inner_brow: self.inner_brow * s,
            pinch: self.pinch * s,
            cheek: self.cheek * s,
            nose: self.nose * s,
            upper_lip: self.upper_lip * s,
            stretch: self.stretch * s,
            lid: self.lid * s,
            pucker: self.pucker * s,
            press: self.press * s,
            furrow: self.furrow * s,
            eye_close: self.eye_close * s,
        }
    }

    /// Every field equal to `v` (unit gains for `v = 1`).
    ///
    /// ```
    /// let g = meshgnn_data::Actions::uniform(1.0);
    /// assert_eq!((g.jaw_deg, g.eye_close), (1.0, 1.0));
    /// ```
    pub fn uniform(v: f64) -> Self {
        Self {
            jaw_deg: v,
            corner_deg: v,
            corner_pull: v,
            brow: v,
            inner_brow: v,
            pinch: v,
            cheek: v,
            nose: v,
            upper_lip: v,
            stretch: v,
            lid: v,
            pucker: v,
            press: v,
            furrow: v,
            eye_close: v,
        }
    }
}

/// The fraction of the lid opening closed for an [`Actions::eye_close`] value `c`: `c` up to
/// 0.85, then saturating towards 0.95 (0.93 at `c = 1`; the lids never quite touch, so the
/// mesh cannot fold);
/// negative values widen the eye, saturating at −0.45.
fn lid_closure(c: f64) -> f64 {
    if c >= 0.85 {
        0.85 + 0.1 * (1.0 - (-(c - 0.85) / 0.1).exp())
    } else if c >= 0.0 {
        c
    } else {
        -0.45 * (-c / 0.45).tanh()
    }
}

/// `v` unchanged up to 60 % of `max` in magnitude, then approaching `max` smoothly (a tanh
/// knee): how far a muscle can pull.
fn soft_limit(v: f64, max: f64) -> f64 {
    let knee = 0.6 * max;
    if v.abs() <= knee {
        v
    } else {
        v.signum() * (knee + (max - knee) * ((v.abs() - knee) / (max - knee)).tanh())
    }
}

/// The actions at a vertex whose side multiplies them by `g` (the style's imbalance; not
/// the jaw, which is one bone), each soft-limited to its anatomical range: jaw 25°, lip
/// corners 24°, corner pull 7 mm, brows 11 mm, inner brows 8 mm, pinch 0.1, cheeks 8 mm,
/// nose 6 mm, upper lip 6 mm, stretch 9 mm, lower lid 3 mm, pucker 1.6, press 4 mm,
/// furrow 6 mm, lids as [`lid_closure`].
fn limited(a: &Actions, g: f64) -> Actions {
    Actions {
        jaw_deg: soft_limit(a.jaw_deg, 25.0),
        corner_deg: soft_limit(a.corner_deg * g, 24.0),
        corner_pull: soft_limit(a.corner_pull * g, 7.0),
        brow: soft_limit(a.brow * g, 11.0),
        inner_brow: soft_limit(a.inner_brow * g, 8.0),
        pinch: soft_limit(a.pinch * g, 0.1),
        cheek: soft_limit(a.cheek * g, 8.0),
        nose: soft_limit(a.nose * g, 6.0),
        upper_lip: soft_limit(a.upper_lip * g, 6.0),
        stretch: soft_limit(a.stretch * g, 9.0),
        lid: soft_limit(a.lid * g, 3.0),
        pucker: soft_limit(a.pucker * g, 1.6),
        press: soft_limit(a.press * g, 4.0),
        furrow: soft_limit(a.furrow * g, 6.0),
        eye_close: a.eye_close * g,
    }
}

/// Mouth-narrowing fraction of an [`Actions::pucker`] value `k`: `0.5 (1 − e^{−1.3k})`.
fn pucker_compression(k: f64) -> f64 {
    0.5 * (1.0 - (-1.3 * k.max(0.0)).exp())
}

/// Height of a strip compressed by the fraction `k` that buckles into an arc of the same
/// length, relative to that length: `√(k(2−k))`, 0 for no compression.
fn buckle(k: f64) -> f64 {
    let k = k.clamp(0.0, 1.0);
    (k * (2.0 - k)).sqrt()
}

/// Compression (1 − stretch) of the skin along a grid row or column below which it stays
/// smooth; beyond it the skin buckles into wrinkles.
const WRINKLE_THRESHOLD: f64 = 0.04;

/// Wrinkle height (mm) per square root of excess compression, for a wrinkle depth of 1.
const WRINKLE_HEIGHT: f64 = 3.5;
/// Outward bunching of compressed skin: a smooth bulge of this many mm per unit of excess
/// compression (up to 0.4), for a wrinkle depth of 1.
const BUNCHING: f64 = 5.0;

/// Rotates `p` about the axis through `centre` along the unit `axis` by `angle` radians;
/// `p` unchanged for a zero angle.
fn rotate_about(p: V3, centre: V3, axis: V3, angle: f64) -> V3 {
    if angle == 0.0 {
        return p;
    }
    add(centre, mul_v(&axis_angle(axis, angle), sub(p, centre)))
}

/// Landmarks measured on one neutral face, so every action follows the subject's geometry.
struct Landmarks {
    /// `b` of `y = b·Y`: millimetres per chart unit vertically (least squares).
    height: f64,
    /// Front-most `z` (mm).
    depth: f64,
    /// Centre of the mouth, the lip corners' rotation centre.
    mouth: V3,
    /// A point on the jaw's rotation axis (parallel to x).
    jaw_pivot: V3,
    /// Eyeball centres, right (−x) then left (+x): the lids rotate about x-parallel axes
    /// through them.
    eyeballs: [V3; 2],
    /// Roots of the upper and lower lip (below the nose, at the chin groove), at the depth of
    /// the lip margins: the lips roll and evert about x-parallel axes through them.
    lip_roots: [V3; 2],
    /// Chart `Y` of the lip roots.
    lip_root_y: [f64; 2],
}

impl Landmarks {
    fn measure(chart: &[[f64; 2]], neutral: &[[f32; 3]], mouth_y: f64) -> Self {
        let (mut depth, mut top, mut yy, mut y_y) = (f64::MIN, 0.0f64, 0.0f64, 0.0f64);
        for (p, c) in neutral.iter().zip(chart) {
            depth = depth.max(f64::from(p[2]));
            top = top.max(f64::from(p[1]).abs());
            yy += f64::from(p[1]) * c[1];
            y_y += c[1] * c[1];
        }
        let depth = if depth.is_finite() { depth } else { 0.0 };
        let height = if y_y > 0.0 && yy > 0.0 {
            yy / y_y
        } else {
            top.max(1.0)
        };
        let nearest = |x: f64, y: f64| -> V3 {
            chart
                .iter()
                .zip(neutral)
                .min_by(|(a, _), (b, _)| {
                    let d = |c: &[f64; 2]| (c[0] - x).powi(2) + (c[1] - y).powi(2);
                    d(a).total_cmp(&d(b))
                })
                .map_or([x * height, y * height, depth], |(_, p)| to_f64(*p))
        };
        let eyeball = |s: f64| sub(nearest(s * EYE_X, EYE_Y), [0.0, 0.0, EYEBALL_RADIUS]);
        let lip_root_y = [mouth_y + 0.14, mouth_y - 0.15];
        // At the lips' depth, so rolling a lip moves its margin back or forth, never across
        // the mouth slit.
        let lip_z = nearest(0.0, mouth_y)[2];
        let root = |y: f64| [0.0, nearest(0.0, y)[1], lip_z];
        Self {
            height,
            depth,
            mouth: [0.0, mouth_y * height, 0.8 * depth],
            jaw_pivot: [0.0, 0.05 * height, -0.1 * depth],
            eyeballs: [eyeball(-1.0), eyeball(1.0)],
            lip_roots: [root(lip_root_y[0]), root(lip_root_y[1])],
            lip_root_y,
        }
    }
}

const X_AXIS: V3 = [1.0, 0.0, 0.0];
const Y_AXIS: V3 = [0.0, 1.0, 0.0];
const Z_AXIS: V3 = [0.0, 0.0, 1.0];

/// Deforms `neutral: #V×3` (a face of `template`) by `actions` — an expression's
/// [`Expression::actions`] scaled by its intensity — performed in the default
/// [`ExpressionStyle`] (symmetric, average skin). See [`apply_styled_actions`].
///
/// ```
/// use meshgnn_data::{Expression, FaceIdentity, FaceTemplate, apply_actions};
/// let t = FaceTemplate::default();
/// let n = t.neutral(&FaceIdentity::mean());
/// let open = apply_actions(&t, &n, &Expression::Surprise.actions());
/// let chin = |v: &[[f32; 3]]| v.iter().map(|p| p[1]).fold(f32::MAX, f32::min);
/// assert!(chin(&open) < chin(&n) - 5.0); // the jaw drops
/// assert_eq!(apply_actions(&t, &n, &Default::default()), n);
/// ```
pub fn apply_actions(template: &FaceTemplate, neutral: &[[f32; 3]], a: &Actions) -> Vec<[f32; 3]> {
    apply_styled_actions(template, neutral, a, &ExpressionStyle::default())
}

/// Deforms `neutral: #V×3` (a face of `template`) by `actions` as performed by a subject of
/// `style`: amplitudes multiplied by the style's left/right imbalance, wrinkles with the
/// style's depth, spacing and phase. The style's gains and easing are *not* applied here —
/// they turn an expression's apex into per-frame actions ([`ExpressionStyle::actions_at`]).
///
/// ```
/// use meshgnn_data::{Expression, ExpressionStyle, FaceIdentity, FaceTemplate, apply_styled_actions};
/// let t = FaceTemplate::new(48, 46)?;
/// let n = t.neutral(&FaceIdentity::mean());
/// let a = Expression::Angry.actions();
/// let lopsided = ExpressionStyle { asymmetry: 0.3, ..Default::default() };
/// let v = apply_styled_actions(&t, &n, &a, &lopsided);
/// // The left (+x) half moves more than the right one.
/// let moved = |left: bool| -> f32 {
///     v.iter().zip(&n).filter(|(_, q)| (q[0] > 0.0) == left)
///         .map(|(p, q)| (p[1] - q[1]).abs() + (p[2] - q[2]).abs()).sum()
/// };
/// assert!(moved(true) > 1.3 * moved(false));
/// # Ok::<(), meshgnn_data::Error>(())
/// ```
pub fn apply_styled_actions(
    template: &FaceTemplate,
    neutral: &[[f32; 3]],
    a: &Actions,
    style: &ExpressionStyle,
) -> Vec<[f32; 3]> {
    if *a == Actions::default() {
        return neutral.to_vec();
    }
    let chart = template.chart();
    let mouth_y = template.mouth_line();
    let lm = Landmarks::measure(&chart, neutral, mouth_y);
    let b = lm.height;
    let mw = MOUTH_HALF_WIDTH;
    let spread = style.spread;
    let moved: Vec<V3> = neutral
        .iter()
        .zip(&chart)
        .map(|(&q, &[x, y])| {
            let mut p = to_f64(q);
            let ax = x.abs();
            let side = if x >= 0.0 { 1.0 } else { -1.0 };
            let g = style.side_gain(x);
            let e = limited(a, g);
            let out = outward(p, lm.depth);

            // Brows: raise along the forehead (an arc about the head centre), inner raise,
            // furrow (drop, draw together, bunch forward), pinch. The frontalis lifts the
            // forehead skin over a wide area above the brows; lowering is limited to 7 mm so
            // the skin below the brows is never compressed to nothing.
            let above = |sigma: f64| {
                let d = y - 0.42;
                gauss(d, if d > 0.0 { 0.22 } else { sigma })
            };
            let w_brow = gauss(ax - EYE_X, 0.18 * spread) * above(0.09);
            let w_inner = gauss(ax - 0.14, 0.09 * spread) * above(0.08);
            let w_furrow = gauss(ax - 0.12, 0.1 * spread) * gauss(y - 0.4, 0.09);
            let furrow = e.furrow;
            let lift =
                e.brow * w_brow + e.inner_brow * w_inner - furrow * (0.4 * w_brow + 0.8 * w_furrow);
            let lift = if lift < 0.0 {
                soft_limit(lift, 7.0)
            } else {
                lift
            };
            if lift != 0.0 {
                let rho = (p[1] * p[1] + p[2] * p[2]).sqrt().max(1.0);
                p = rotate_about(p, [0.0; 3], X_AXIS, -lift / rho);
            }

            // Eyelids: a monotone remap of the chart height about the eye — applied after the
            // brows' shift, so the composition stays monotone and skin pushed down by the
            // brows is taken up by the lid opening — turned into a rotation about the
            // eyeball's x-parallel axis (arc length = the remap's shift).
            for (k, s) in [-1.0, 1.0].into_iter().enumerate() {
                let (dx, dy) = (x - s * EYE_X, y + lift / b - EYE_Y);
                if dx.abs() >= EYE_HALF_WIDTH || !(-0.15..0.2).contains(&dy) {
                    continue;
                }
                let raise = (e.lid + 0.3 * e.cheek) / b;
                let f = lid_closure(e.eye_close);
                if raise == 0.0 && f == 0.0 {
                    continue;
                }
                let (up, lo) = lid_margins(s * dx);
                let opening = up - lo;
                let r = raise.clamp(-0.4 * opening, 0.5 * opening);
                let new_lo = lo + r;
                let new_up = new_lo + (1.0 - f) * (up - new_lo);
                let shift = if dy < lo {
                    r * smoothstep(lo - 0.07, lo, dy)
                } else if dy <= up {
                    let t = if opening > 0.0 {
                        (dy - lo) / opening
                    } else {
                        0.0
                    };
                    new_lo + t * (new_up - new_lo) - dy
                } else {
                    (new_up - up) * smoothstep(up + 0.11, up, dy)
                };
                let c = lm.eyeballs[k];
                let rho = ((p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2))
                    .sqrt()
                    .max(1.0);
                p = rotate_about(p, c, X_AXIS, -shift * b / rho);
            }

            if furrow > 0.0 {
                let k = 0.5 * (1.0 - (-furrow / 8.0).exp());
                let w = gauss(y - 0.38, 0.1) * smoothstep(0.4, 0.08, ax);
                p[0] -= k * w * p[0];
                let bunch = 4.0 * buckle(k * w) * gauss(x, 0.05) * gauss(y - 0.36, 0.06);
                p = add(p, scale(out, bunch));
            }
            p[0] -= e.pinch * p[0] * w_brow;

            // Cheeks: lift and quadratic bulge, deeper nasolabial folds.
            let cheek = e.cheek;
            if cheek != 0.0 {
                let [cx, cy] = style.corner_shift;
                let w = gauss(ax - 0.42 - cx, 0.15 * spread) * gauss(y + 0.05 - cy, 0.14 * spread);
                p[1] += cheek * w;
                p[2] += (0.4 * cheek + 0.06 * cheek * cheek.abs()) * w;
                // Signed distance to the fold's line, positive on the cheek side.
                let (fa, fb) = nasolabial_fold(side);
                let (ux, uy) = (fb[0] - fa[0], fb[1] - fa[1]);
                let lateral =
                    side * (ux * (y - fa[1]) - uy * (x - fa[0])) / (ux * ux + uy * uy).sqrt();
                let d = segment_distance(x, y, fa, fb);
                let fold = 0.35 * cheek * gauss(lateral - 0.035, 0.025) * gauss(d, 0.06)
                    - 0.3 * cheek * gauss(d, 0.015);
                p = add(p, scale(out, fold));
            }

            // Nose wrinkle: the sides of the nose lift, the nostrils flare.
            let nose = e.nose;
            p[1] += nose * gauss(ax - 0.08, 0.08) * gauss(y - 0.1, 0.08);
            p[0] += side * 0.15 * nose * gauss(ax - 0.1, 0.05) * gauss(y + 0.06, 0.04);

            // Lips: pucker (narrow, buckle forward, evert), press (roll in, flatten, chin
            // up), upper-lip raise (lift, evert). Each lip rotates about its root.
            let lips = smoothstep(mw, mw - 0.1, ax);
            let upper = y > mouth_y;
            let root = if upper { 0 } else { 1 };
            let w_lip = lips * smoothstep(lm.lip_root_y[root], mouth_y, y);
            let k = pucker_compression(e.pucker);
            if k > 0.0 {
                let r = ((x / (mw + 0.14)).powi(2) + ((y - mouth_y) / 0.17).powi(2)).sqrt();
                let w = smoothstep(1.0, 0.35, r);
                p[0] -= k * w * p[0];
                p[2] += 9.0 * buckle(k * w) * gauss(y - mouth_y, 0.08);
            }
            let press = e.press;
            let raise = e.upper_lip;
            let roll = if upper {
                0.035 * press - 0.6 * k - 0.04 * raise
            } else {
                -0.035 * press + 0.6 * k
            };
            p = rotate_about(p, lm.lip_roots[root], X_AXIS, roll * w_lip);
            p[2] -= 0.4 * press * lips * gauss(y - mouth_y, 0.07);
            p[1] += 0.5 * press * gauss(x, 0.15) * gauss(y + 0.6, 0.08);
            if upper {
                p[1] += raise * gauss(x, 0.25) * lips * smoothstep(-0.1, -0.26, y);
            }

            // Jaw: a rotation about the condyles' axis with a sharp transition across the
            // mouth opening (lens-shaped: wider towards the corners, then the cheeks), plus
            // the condyles' forward glide once the opening passes 6°.
            let front = smoothstep(0.95, 0.7, ax);
            let band = 0.004
                + style.jaw_band
                    * (0.06 * (ax / mw).min(1.0).powi(2) + 0.2 * smoothstep(mw, mw + 0.3, ax));
            let w_jaw = smoothstep(mouth_y + band, mouth_y - band, y) * front;
            if e.jaw_deg != 0.0 && w_jaw > 0.0 {
                p = rotate_about(p, lm.jaw_pivot, X_AXIS, e.jaw_deg.to_radians() * w_jaw);
                let glide = 0.25 * style.jaw_glide * (e.jaw_deg - 6.0).max(0.0);
                p = add(p, scale([0.0, -0.3, 1.0], glide * w_jaw));
            }

            // Lip corners: rotation about the mouth's forward axis, a pull backwards, and
            // the stretch sliding them around the head (about the vertical axis).
            let [cx, cy] = style.corner_shift;
            let w_corner =
                gauss(ax - mw - cx, 0.12 * spread) * gauss(y - mouth_y - cy, 0.1 * spread);
            if w_corner > 1e-6 {
                let angle = side * e.corner_deg.to_radians() * w_corner;
                p = rotate_about(p, lm.mouth, Z_AXIS, angle);
                p[2] -= e.corner_pull * w_corner;
                let stretch = e.stretch * w_corner;
                if stretch != 0.0 {
                    let centre = [0.0, 0.0, -0.1 * lm.depth];
                    let rho = (p[0].powi(2) + (p[2] - centre[2]).powi(2)).sqrt().max(1.0);
                    p = rotate_about(p, centre, Y_AXIS, side * stretch / rho);
                }
            }
            p
        })
        .collect();
    let wrinkles = compression_wrinkles(template, &chart, neutral, &moved, mouth_y, style);
    moved
        .iter()
        .zip(&wrinkles)
        .map(|(&p, &w)| {
            to_f32(if w == 0.0 {
                p
            } else {
                add(p, scale(outward(p, lm.depth), w))
            })
        })
        .collect()
}

/// The outward direction at `p` for relief: from a point `0.1·depth` behind the head
/// centre.
fn outward(p: V3, depth: f64) -> V3 {
    normalize([p[0], p[1], p[2] + 0.1 * depth])
}

/// Skin compressed by more than [`WRINKLE_THRESHOLD`] buckles: the relief (mm, along the
/// outward direction) of every vertex of `moved: #V×3` (the deformed face) relative to
/// `neutral: #V×3`. Compression is measured along the grid's rows and columns (central
/// differences, not across the mouth slit); a row-wise compression `c` raises lines across
/// the row (vertical lines, e.g. between furrowed brows or above puckered lips), a
/// column-wise one lines across the column (horizontal, e.g. on a raised forehead or above
/// raised cheeks), each of height `depth·WRINKLE_HEIGHT·√(c − threshold)` following the subject's
/// wavy wrinkle pattern (height [`WRINKLE_HEIGHT`]). The eye openings and the lip margins, which fold rather than
/// wrinkle, are left out. Lines are at most 16 % of their compressed wavelength high, so
/// the relief never folds. Compressed skin also bunches outwards by
/// `depth·BUNCHING·min(c − threshold, 0.4)`.
fn compression_wrinkles(
    template: &FaceTemplate,
    chart: &[[f64; 2]],
    neutral: &[[f32; 3]],
    moved: &[V3],
    mouth_y: f64,
    style: &ExpressionStyle,
) -> Vec<f64> {
    let (columns, rows) = template.grid();
    let tau = std::f64::consts::TAU;
    let (lambda_h, lambda_v) = (0.1 * style.wrinkle_spacing, 0.075 * style.wrinkle_spacing);
    // Height of one family of lines at excess compression `c`: `depth·H·√c`, at most 16 % of
    // the compressed wavelength (mm; about 80 mm per chart unit across, 100 up) so the
    // slopes stay below 1 on the grid.
    let height = |c: f64, lambda_mm: f64| {
        (WRINKLE_HEIGHT * style.wrinkle_depth * c.sqrt()).min(0.16 * lambda_mm * (1.0 - c))
    };
    let phase = style.wrinkle_phase;
    let bunching = |c: f64| BUNCHING * style.wrinkle_depth * c.min(0.4);
    let across_slit = |k0: usize, k1: usize| {
        let (a, b) = (chart[k0], chart[k1]);
        (a[1] - mouth_y) * (b[1] - mouth_y) < 0.0
            && a[0].abs().max(b[0].abs()) < MOUTH_HALF_WIDTH + 0.03
    };
    let strain = |k0: usize, k1: usize| -> f64 {
        let before = norm(sub(to_f64(neutral[k1]), to_f64(neutral[k0])));
        let after = norm(sub(moved[k1], moved[k0]));
        if before > 0.0 { after / before } else { 1.0 }
    };
    (0..moved.len())
        .map(|k| {
            let (i, j) = (k % columns, k / columns);
            let [x, y] = chart[k];
            // Folding regions: the lid openings and the lip margins.
            let dx = x.abs() - EYE_X;
            let (up, lo) = lid_margins(dx);
            if (dx.abs() < EYE_HALF_WIDTH + 0.02 && y > EYE_Y + lo - 0.03 && y < EYE_Y + up + 0.03)
                || (x.abs() < MOUTH_HALF_WIDTH + 0.04 && (y - mouth_y).abs() < 0.04)
            {
                return 0.0;
            }
            let left = if i > 0 { k - 1 } else { k };
            let right = if i + 1 < columns { k + 1 } else { k };
            let mut down = if j > 0 { k - columns } else { k };
            let mut up = if j + 1 < rows { k + columns } else { k };
            if down != k && across_slit(down, k) {
                down = k;
            }
            if up != k && across_slit(k, up) {
                up = k;
            }
            let mut relief = 0.0;
            if left != right {
                let c = 1.0 - strain(left, right) - WRINKLE_THRESHOLD;
                if c > 0.0 {
                    let xw = x + 0.03 * (9.0 * y + phase).sin();
                    relief += height(c, 80.0 * lambda_h) * (tau * xw / lambda_h + phase).sin()
                        + bunching(c);
                }
            }
            if down != up {
                let c = 1.0 - strain(down, up) - WRINKLE_THRESHOLD;
                if c > 0.0 {
                    let yw = y + 0.025 * (7.0 * x + 2.0 * phase).sin();
                    relief += height(c, 100.0 * lambda_v)
                        * (tau * yw / lambda_v + 1.7 * phase).sin()
                        + bunching(c);
                }
            }
            relief
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{FaceIdentity, FaceSetConfig};

    /// Index of the vertex whose chart position is nearest `(x, y)`.
    fn nearest(chart: &[[f64; 2]], x: f64, y: f64) -> usize {
        let d = |c: &[f64; 2]| (c[0] - x).powi(2) + (c[1] - y).powi(2);
        (0..chart.len())
            .min_by(|&a, &b| d(&chart[a]).total_cmp(&d(&chart[b])))
            .unwrap()
    }

    fn distance(a: [f32; 3], b: [f32; 3]) -> f64 {
        norm(sub(to_f64(a), to_f64(b)))
    }

    /// Largest deviation (mm) of the half-intensity face from the average of the neutral and
    /// full-intensity faces: 0 for a deformation linear in the intensity.
    fn deviation_from_linear(t: &FaceTemplate, n: &[[f32; 3]], a: Actions) -> f64 {
        let full = apply_actions(t, n, &a);
        let half = apply_actions(t, n, &a.scaled(0.5));
        let mut worst = 0.0f64;
        for ((f, h), z) in full.iter().zip(&half).zip(n) {
            for k in 0..3 {
                let lin = 0.5 * (f64::from(f[k]) + f64::from(z[k]));
                worst = worst.max((lin - f64::from(h[k])).abs());
            }
        }
        worst
    }

    #[test]
    fn pucker_pushes_the_lips_forward_and_the_corners_together() {
        let t = FaceTemplate::default();
        let n = t.neutral(&FaceIdentity::mean());
        let chart = t.chart();
        let m = t.mouth_line();
        let pucker = Actions {
            pucker: 1.0,
            ..Default::default()
        };
        let v = apply_actions(&t, &n, &pucker);
        // The mouth's midpoint: between the two lip margins at the midline.
        let (up, lo) = (
            nearest(&chart, 0.0, m + 0.01),
            nearest(&chart, 0.0, m - 0.01),
        );
        let forward = |p: &[[f32; 3]]| 0.5 * (f64::from(p[up][2]) + f64::from(p[lo][2]));
        assert!(
            forward(&v) > forward(&n) + 5.0,
            "midpoint {} → {} mm",
            forward(&n),
            forward(&v)
        );
        // The corners come closer: 1 − 0.36 × 0.52 of the width (compression × weight).
        let (left, right) = (
            nearest(&chart, MOUTH_HALF_WIDTH, m),
            nearest(&chart, -MOUTH_HALF_WIDTH, m),
        );
        let width = |p: &[[f32; 3]]| distance(p[left], p[right]);
        assert!(
            width(&v) < 0.85 * width(&n),
            "corners {} → {} mm apart",
            width(&n),
            width(&v)
        );
    }

    #[test]
    fn eye_closure_brings_the_upper_lid_down_to_the_lower_lid() {
        let t = FaceTemplate::default();
        let n = t.neutral(&FaceIdentity::mean());
        let chart = t.chart();
        let (columns, rows) = t.grid();
        for s in [-1.0, 1.0] {
            // The eye's centre column; its rows at or just beyond the two lid margins.
            let centre = nearest(&chart, s * EYE_X, EYE_Y);
            let cells: Vec<usize> = (0..rows).map(|j| j * columns + centre % columns).collect();
            let (up, lo) = lid_margins(s * chart[centre][0] - EYE_X);
            let upper = *cells
                .iter()
                .filter(|&&k| chart[k][1] >= EYE_Y + up)
                .min_by(|&&a, &&b| chart[a][1].total_cmp(&chart[b][1]))
                .unwrap();
            let lower = *cells
                .iter()
                .filter(|&&k| chart[k][1] <= EYE_Y + lo)
                .max_by(|&&a, &&b| chart[a][1].total_cmp(&chart[b][1]))
                .unwrap();
            let gap = |c: f64| {
                let v = apply_actions(
                    &t,
                    &n,
                    &Actions {
                        eye_close: c,
                        ..Default::default()
                    },
                );
                distance(v[upper], v[lower])
            };
            let (open, half, closed) = (gap(0.0), gap(0.5), gap(1.0));
            assert!(open > 9.0, "open lids {open} mm apart");
            // 7 % of the opening is left (saturation), plus up to a row of the grid and the
            // upper lid's thicker margin.
            assert!(
                closed < 2.5 && closed < 0.2 * open,
                "closed: {open} → {closed} mm"
            );
            assert!(half < 0.7 * open && half > 2.0 * closed, "half: {half} mm");
            // Widening lifts the upper lid.
            assert!(gap(-0.4) > open + 2.0);
        }
    }

    #[test]
    fn new_actions_are_non_linear_in_intensity() {
        let t = FaceTemplate::default();
        let n = t.neutral(&FaceIdentity::mean());
        let z = Actions::default();
        for (name, a, at_least) in [
            ("pucker", Actions { pucker: 1.0, ..z }, 0.5),
            (
                "eye closure",
                Actions {
                    eye_close: 1.0,
                    ..z
                },
                0.3,
            ),
            ("furrow", Actions { furrow: 5.0, ..z }, 0.2),
            ("press", Actions { press: 2.5, ..z }, 0.05),
        ] {
            let d = deviation_from_linear(&t, &n, a);
            assert!(d > at_least, "{name}: max deviation from linear {d} mm");
        }
    }

    #[test]
    fn two_subjects_perform_the_same_apex_differently() {
        // Same face, same expression, same extremeness: only the style differs.
        let t = FaceTemplate::default();
        let n = t.neutral(&FaceIdentity::mean());
        let cfg = FaceSetConfig::default();
        for e in Expression::ALL {
            let apex = e.actions().scaled(0.8);
            let perform = |i: usize| {
                let style = cfg.style(i);
                apply_styled_actions(&t, &n, &style.actions_at(&apex, 1.0), &style)
            };
            let (a, b) = (perform(0), perform(1));
            let diffs: Vec<f64> = a.iter().zip(&b).map(|(p, q)| distance(*p, *q)).collect();
            let max = diffs.iter().copied().fold(0.0, f64::max);
            let mean = diffs.iter().sum::<f64>() / diffs.len() as f64;
            assert!(max > 1.0 && mean > 0.02, "{e:?}: max {max}, mean {mean} mm");
        }
    }

    #[test]
    fn zero_actions_leave_the_face_unchanged_for_any_style() {
        let t = FaceTemplate::new(40, 38).unwrap();
        let n = t.neutral(&FaceIdentity::random(3));
        let style = FaceSetConfig::default().style(5);
        assert_eq!(apply_styled_actions(&t, &n, &Actions::default(), &style), n);
        let still = style.actions_at(&Expression::Fear.actions(), 0.0);
        assert_eq!(apply_styled_actions(&t, &n, &still, &style), n);
    }

    #[test]
    fn expressions_are_non_linear_in_intensity() {
        // A rotation is not linear: half the jaw angle is not half the displacement.
        let t = FaceTemplate::default();
        let n = t.neutral(&FaceIdentity::mean());
        let a = Expression::Surprise.actions();
        let full = apply_actions(&t, &n, &a);
        let half = apply_actions(&t, &n, &a.scaled(0.5));
        let mut worst = 0.0f64;
        for ((f, h), z) in full.iter().zip(&half).zip(&n) {
            for k in 0..3 {
                let lin = 0.5 * (f64::from(f[k]) + f64::from(z[k]));
                worst = worst.max((lin - f64::from(h[k])).abs());
            }
        }
        assert!(worst > 0.2, "max deviation from linear {worst} mm");
    }

    #[test]
    fn happy_lifts_corners_and_sad_lowers_them() {
        let t = FaceTemplate::default();
        let n = t.neutral(&FaceIdentity::mean());
        let chart = t.chart();
        let corner = chart
            .iter()
            .enumerate()
            .min_by(|(_, a), (_, b)| {
                let d =
                    |c: &[f64; 2]| (c[0] - MOUTH_HALF_WIDTH).abs() + (c[1] - t.mouth_line()).abs();
                d(a).total_cmp(&d(b))
            })
            .map(|(i, _)| i)
            .unwrap();
        let happy = apply_actions(&t, &n, &Expression::Happy.actions());
        let sad = apply_actions(&t, &n, &Expression::Sad.actions());
        assert!(happy[corner][1] > n[corner][1] + 1.0);
        assert!(sad[corner][1] < n[corner][1] - 1.0);
    }
}
