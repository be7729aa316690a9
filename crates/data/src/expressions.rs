//! The six 4DFAB expressions (happy, sad, surprise, angry, disgust, fear — thesis ch. 4.4.1)
//! as region-driven deformations of a neutral face from [`crate::FaceTemplate`].
//!
//! Each expression combines a few muscle-like actions, each acting on a smooth region of the
//! face chart: jaw opening (a rotation of the lower face about a horizontal axis near the
//! ears), lip-corner curl (rotation of the mouth corners about the mouth's forward axis, plus
//! a backward pull), brow raise / lower / pinch, inner-brow raise, cheek raise, nose wrinkle,
//! upper-lip raise, mouth stretch and eye widening / squint. Rotations make the deformation
//! non-linear in the intensity, which is what the ch. 4 generator must learn.

use crate::face_template::{EYE_X, FaceTemplate, MOUTH_HALF_WIDTH, gauss, smoothstep};
use crate::vec3::{V3, add, axis_angle, mul_v, sub, to_f32, to_f64};

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

    /// The actions at full intensity.
    pub fn actions(self) -> Actions {
        let z = Actions::default();
        match self {
            Expression::Happy => Actions {
                jaw_deg: 6.0,
                corner_deg: 16.0,
                corner_pull: 4.0,
                cheek: 4.0,
                lid: 1.5,
                ..z
            },
            Expression::Sad => Actions {
                jaw_deg: 1.5,
                corner_deg: -14.0,
                inner_brow: 4.0,
                brow: -1.0,
                ..z
            },
            Expression::Surprise => Actions {
                jaw_deg: 20.0,
                brow: 8.0,
                lid: -1.5,
                ..z
            },
            Expression::Angry => Actions {
                brow: -4.0,
                pinch: 0.12,
                corner_deg: -5.0,
                nose: 1.0,
                ..z
            },
            Expression::Disgust => Actions {
                jaw_deg: 4.0,
                upper_lip: 4.0,
                nose: 3.0,
                brow: -2.0,
                corner_deg: -8.0,
                cheek: 2.0,
                ..z
            },
            Expression::Fear => Actions {
                jaw_deg: 10.0,
                stretch: 6.0,
                inner_brow: 5.0,
                brow: 3.0,
                lid: -1.5,
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
    /// Whole-brow raise (mm, negative lowers).
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
    /// Mouth stretch (mm sideways at the corners).
    pub stretch: f64,
    /// Lower-lid raise (mm; negative widens the eyes).
    pub lid: f64,
}

impl Actions {
    /// Every amplitude multiplied by `s` (a subject's style or an intensity).
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
        }
    }
}

/// Deforms `neutral: #V×3` (a face of `template`) by `actions` — an expression's
/// [`Expression::actions`] scaled by its intensity.
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
    let chart = template.chart();
    let mouth_y = template.mouth_line();
    // Mouth centre and jaw pivot from the neutral geometry (scale-aware).
    let (mut top, mut depth) = (0.0f64, 0.0f64);
    for p in neutral {
        top = top.max(f64::from(p[1]).abs());
        depth = depth.max(f64::from(p[2]));
    }
    let height = top.max(1.0);
    let mouth: V3 = [0.0, mouth_y * height, 0.8 * depth];
    let pivot: V3 = [0.0, 0.05 * height, -0.1 * depth];
    let mw = MOUTH_HALF_WIDTH;
    neutral
        .iter()
        .zip(&chart)
        .map(|(&q, &[x, y])| {
            let mut p = to_f64(q);
            let ax = x.abs();
            let front = smoothstep(0.95, 0.7, ax);
            // Jaw: sharp transition across the mouth opening, wider towards the cheeks.
            // Lens-shaped opening: the band widens towards the corners, then the cheeks.
            let band =
                0.004 + 0.06 * (ax / mw).min(1.0).powi(2) + 0.2 * smoothstep(mw, mw + 0.3, ax);
            let w_jaw = smoothstep(mouth_y + band, mouth_y - band, y) * front;
            if a.jaw_deg != 0.0 && w_jaw > 0.0 {
                let r = axis_angle([1.0, 0.0, 0.0], a.jaw_deg.to_radians() * w_jaw);
                p = add(pivot, mul_v(&r, sub(p, pivot)));
            }
            // Lip corners: rotation about the mouth's forward axis, and a pull backwards.
            let side = if x >= 0.0 { 1.0 } else { -1.0 };
            let w_corner = gauss(ax - mw, 0.12) * gauss(y - mouth_y, 0.1);
            if w_corner > 1e-6 {
                let r = axis_angle([0.0, 0.0, 1.0], side * a.corner_deg.to_radians() * w_corner);
                p = add(mouth, mul_v(&r, sub(p, mouth)));
                p[2] -= a.corner_pull * w_corner;
                p[0] += side * a.stretch * w_corner;
            }
            let eye = gauss(ax - EYE_X, 0.18);
            let w_brow = eye * gauss(y - 0.42, 0.09);
            p[1] += a.brow * w_brow;
            p[0] -= a.pinch * p[0] * w_brow;
            p[1] += a.inner_brow * gauss(ax - 0.12, 0.09) * gauss(y - 0.42, 0.08);
            let w_cheek = gauss(ax - 0.4, 0.15) * gauss(y + 0.05, 0.14);
            p[1] += a.cheek * w_cheek;
            p[2] += 0.5 * a.cheek * w_cheek;
            p[1] += a.nose * gauss(ax - 0.08, 0.08) * gauss(y - 0.1, 0.08);
            p[1] += a.upper_lip * gauss(x, 0.25) * gauss(y + 0.28, 0.05);
            p[1] += a.lid * gauss(ax - EYE_X, 0.09) * gauss(y - 0.19, 0.035);
            to_f32(p)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::FaceIdentity;

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
