//! How one subject performs the facial actions of [`crate::Expression`]: per-action gains,
//! a left/right imbalance, the timing of the upper and lower face within a sequence, and the
//! subject's skin (depth, spacing and phase of the wrinkles that strong actions raise).
//!
//! The thesis (ch. 4.4.2) explains the generator's remaining errors around the mouth and
//! brows by exactly this: "each identity expresses its emotions in different ways and
//! varying extents", which a subject-independent model conditioned on the expression label
//! alone cannot know. The synthetic set reproduces it so that the linear blendshape baseline
//! of Table 4.2 and the spiral decoder can be compared on data that is neither linear nor
//! subject-independent.
//!
//! # Conventions
//! - Wrinkles: wherever an action compresses the skin by more than 4 % it buckles into lines
//!   of the subject's depth, spacing and phase (see [`crate::apply_styled_actions`]).
//! - Gains multiply the amplitudes of [`crate::Actions`], field by field, on top of the
//!   sequence's extremeness; 1 everywhere is the textbook performance of
//!   [`crate::Expression::actions`].
//! - `asymmetry` > 0 makes the subject's left side (+x, the face's own left) stronger:
//!   amplitudes are multiplied by `1 + asymmetry·tanh(x / 0.05)` at chart position `x`.
//! - The mouth group (jaw, lip corners, stretch, upper lip, pucker, press) follows the motion
//!   value `m ∈ [0, 1]` as `m^lower_easing`, the eye and brow group (brows, furrow, pinch,
//!   cheeks, nose, lids) as `m^upper_easing`: both reach the apex together, but one leads.

use rand::Rng;
use rand::SeedableRng;
use rand::rngs::StdRng;
use rand_distr::{Distribution, Normal};

use crate::expressions::Actions;

/// One subject's way of performing the expressions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExpressionStyle {
    /// Multiplier of each action amplitude (each field a gain, typically 0.5-1.7).
    pub gains: Actions,
    /// Left/right imbalance in `[−0.3, 0.3]` (positive: the left, +x, side acts more).
    pub asymmetry: f64,
    /// Exponent of the motion value for the eye and brow actions (0.7-1.4).
    pub upper_easing: f64,
    /// Exponent of the motion value for the mouth actions (0.7-1.4).
    pub lower_easing: f64,
    /// Width multiplier of the lip-corner, cheek and brow regions (0.8-1.25: a broad or a
    /// narrow smile).
    pub spread: f64,
    /// Shift (chart units, outwards and up) of the lip-corner and cheek regions: where the
    /// subject's smile muscles pull (each within ±0.04).
    pub corner_shift: [f64; 2],
    /// How much of the cheeks follows the opening jaw (multiplier of the lens-shaped
    /// transition band, 0.6-1.5).
    pub jaw_band: f64,
    /// Forward glide of the jaw's condyles per degree of opening beyond 6°, as a multiple of
    /// 0.25 mm (0.5-1.5); the glide starts past 6°.
    pub jaw_glide: f64,
    /// Wrinkle depth multiplier (0.3-1.5; thin or deep skin).
    pub wrinkle_depth: f64,
    /// Wrinkle spacing multiplier (0.85-1.3).
    pub wrinkle_spacing: f64,
    /// Wrinkle phase (radians, `[0, 2π)`): where the subject's lines lie.
    pub wrinkle_phase: f64,
}

impl Default for ExpressionStyle {
    /// The textbook performance: unit gains, symmetric, linear easing, average skin.
    fn default() -> Self {
        Self {
            gains: Actions::uniform(1.0),
            asymmetry: 0.0,
            upper_easing: 1.0,
            lower_easing: 1.0,
            spread: 1.0,
            corner_shift: [0.0, 0.0],
            jaw_band: 1.0,
            jaw_glide: 1.0,
            wrinkle_depth: 1.0,
            wrinkle_spacing: 1.0,
            wrinkle_phase: 0.0,
        }
    }
}

impl ExpressionStyle {
    /// A random style from `seed`. A balance `β ~ U(−1, 1)` moves effort between the mouth
    /// (gain `e^{0.35β}`) and the eyes and brows (`e^{−0.35β}`) — one subject smiles mostly
    /// with the mouth, another with the eyes; the jaw opening varies by a log-normal factor
    /// (σ = 0.25), every action by another (σ = 0.2); gains are clipped to `[0.45, 1.7]`.
    ///
    /// ```
    /// use meshgnn_data::ExpressionStyle;
    /// let a = ExpressionStyle::random(3);
    /// assert_eq!(a, ExpressionStyle::random(3));
    /// assert_ne!(a, ExpressionStyle::random(4));
    /// assert!((0.45..=1.7).contains(&a.gains.jaw_deg) && a.asymmetry.abs() <= 0.3);
    /// ```
    pub fn random(seed: u64) -> Self {
        let mut rng = StdRng::seed_from_u64(seed);
        let mut log_normal = |sd: f64| {
            Normal::new(0.0, sd)
                .map(|d| d.sample(&mut rng))
                .unwrap_or(0.0)
                .clamp(-2.5 * sd, 2.5 * sd)
                .exp()
        };
        let jaw = log_normal(0.25);
        let mut each = [0.0f64; 15];
        for g in &mut each {
            *g = log_normal(0.2);
        }
        let asymmetry = Normal::new(0.0f64, 0.12)
            .map(|d| d.sample(&mut rng))
            .unwrap_or(0.0)
            .clamp(-0.3, 0.3);
        let balance: f64 = rng.random_range(-1.0..1.0);
        let (mouth, eyes) = ((0.35 * balance).exp(), (-0.35 * balance).exp());
        let g = |k: usize, group: f64| (each[k] * group).clamp(0.45, 1.7);
        let gains = Actions {
            jaw_deg: (jaw * each[0] * mouth).clamp(0.45, 1.7),
            corner_deg: g(1, mouth),
            corner_pull: g(2, mouth),
            brow: g(3, eyes),
            inner_brow: g(4, eyes),
            pinch: g(5, eyes),
            cheek: g(6, eyes),
            nose: g(7, eyes),
            upper_lip: g(8, mouth),
            stretch: g(9, mouth),
            lid: g(10, eyes),
            pucker: g(11, mouth),
            press: g(12, mouth),
            furrow: g(13, eyes),
            eye_close: g(14, eyes),
        };
        Self {
            gains,
            asymmetry,
            upper_easing: rng.random_range(0.7..1.4),
            lower_easing: rng.random_range(0.7..1.4),
            spread: rng.random_range(0.8..1.25),
            corner_shift: [rng.random_range(-0.04..0.04), rng.random_range(-0.04..0.04)],
            jaw_band: rng.random_range(0.6..1.5),
            jaw_glide: rng.random_range(0.5..1.5),
            wrinkle_depth: rng.random_range(0.3..1.5),
            wrinkle_spacing: rng.random_range(0.85..1.3),
            wrinkle_phase: rng.random_range(0.0..std::f64::consts::TAU),
        }
    }

    /// The actions of this subject at motion value `motion ∈ [0, 1]` of a sequence whose apex
    /// actions are `apex` (an expression's [`crate::Expression::actions`] scaled by the
    /// sequence's extremeness): gains applied, each group eased by its exponent.
    ///
    /// ```
    /// use meshgnn_data::{Expression, ExpressionStyle};
    /// let apex = Expression::Happy.actions();
    /// let style = ExpressionStyle { lower_easing: 2.0, ..Default::default() };
    /// let half = style.actions_at(&apex, 0.5);
    /// assert_eq!(half.cheek, 0.5 * apex.cheek); // eyes: linear
    /// assert_eq!(half.corner_deg, 0.25 * apex.corner_deg); // mouth: lags behind
    /// assert_eq!(style.actions_at(&apex, 1.0), apex);
    /// ```
    pub fn actions_at(&self, apex: &Actions, motion: f64) -> Actions {
        let m = motion.clamp(0.0, 1.0);
        let (up, low) = (m.powf(self.upper_easing), m.powf(self.lower_easing));
        let g = &self.gains;
        Actions {
            jaw_deg: apex.jaw_deg * g.jaw_deg * low,
            corner_deg: apex.corner_deg * g.corner_deg * low,
            corner_pull: apex.corner_pull * g.corner_pull * low,
            brow: apex.brow * g.brow * up,
            inner_brow: apex.inner_brow * g.inner_brow * up,
            pinch: apex.pinch * g.pinch * up,
            cheek: apex.cheek * g.cheek * up,
            nose: apex.nose * g.nose * up,
            upper_lip: apex.upper_lip * g.upper_lip * low,
            stretch: apex.stretch * g.stretch * low,
            lid: apex.lid * g.lid * up,
            pucker: apex.pucker * g.pucker * low,
            press: apex.press * g.press * low,
            furrow: apex.furrow * g.furrow * up,
            eye_close: apex.eye_close * g.eye_close * up,
        }
    }

    /// The amplitude multiplier of the imbalance at chart position `x`:
    /// `1 + asymmetry·tanh(x / 0.05)`.
    pub(crate) fn side_gain(&self, x: f64) -> f64 {
        1.0 + self.asymmetry * (x / 0.05).tanh()
    }
}
