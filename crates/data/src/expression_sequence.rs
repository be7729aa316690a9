//! 4D expression sequences with the motion labels of thesis ch. 4.4.1: each sequence has a
//! neutral start, a linear onset, an apex plateau and a linear offset back to neutral; each
//! frame's label is the one-hot expression scaled by the motion value, and the apex value is
//! scaled per subject by the intensity `s_i` of eq. 4.3.
//!
//! Each subject performs the expressions in its own [`ExpressionStyle`] (gains per action,
//! left/right imbalance, easing, wrinkles), on top of the per-sequence extremeness.
//!
//! Subjects are split subject-disjointly like 4DFAB in the thesis (153 train / 27 test of 180).

use rand::Rng;
use rand::SeedableRng;
use rand::rngs::StdRng;

use crate::error::{Result, invalid};
use crate::expression_style::ExpressionStyle;
use crate::expressions::{Expression, apply_styled_actions};
use crate::face_template::{FaceIdentity, FaceTemplate};
use crate::vec3::item_seed;

/// Stream tag of the per-subject style seed (`item_seed(item_seed(seed, index), tag)`).
const STYLE_STREAM: u64 = 0x0053_5459_4C45;

/// Frame timing of one sequence (frame indices, `0 ≤ onset < apex_start ≤ apex_end <
/// offset_end < frames`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SequenceTiming {
    /// Number of frames, 60-100 for generated sequences.
    pub frames: usize,
    /// Last neutral frame; the onset starts after it.
    pub onset: usize,
    /// First apex frame.
    pub apex_start: usize,
    /// Last apex frame.
    pub apex_end: usize,
    /// First neutral frame after the offset.
    pub offset_end: usize,
}

impl SequenceTiming {
    /// A random subject-dependent timing from `seed`: 60-100 frames, onset after 5-20 % of
    /// the sequence, onset and offset 15-25 % long, apex 15-30 %.
    ///
    /// ```
    /// let t = meshgnn_data::SequenceTiming::random(4);
    /// assert!((60..=100).contains(&t.frames));
    /// assert!(t.onset < t.apex_start && t.apex_start <= t.apex_end && t.apex_end < t.offset_end);
    /// assert!(t.offset_end < t.frames);
    /// ```
    pub fn random(seed: u64) -> Self {
        let mut rng = StdRng::seed_from_u64(seed);
        let frames = rng.random_range(60..=100usize);
        let f = frames as f64;
        let part =
            |rng: &mut StdRng, lo: f64, hi: f64| ((rng.random_range(lo..hi) * f) as usize).max(1);
        let onset = part(&mut rng, 0.05, 0.2);
        let apex_start = onset + part(&mut rng, 0.15, 0.25);
        let apex_end = apex_start + part(&mut rng, 0.15, 0.3);
        let offset_end = (apex_end + part(&mut rng, 0.15, 0.25)).min(frames - 1);
        Self {
            frames,
            onset,
            apex_start,
            apex_end,
            offset_end,
        }
    }

    /// The motion value of `frame` in `[0, 1]` (ch. 4.4.1, Fig. 4.2): 0 neutral, linear onset,
    /// 1 at the apex, linear offset, 0 after.
    ///
    /// ```
    /// use meshgnn_data::SequenceTiming;
    /// let t = SequenceTiming { frames: 60, onset: 10, apex_start: 20, apex_end: 30, offset_end: 40 };
    /// assert_eq!(t.motion(5), 0.0);
    /// assert_eq!(t.motion(15), 0.5);
    /// assert_eq!(t.motion(25), 1.0);
    /// assert_eq!(t.motion(35), 0.5);
    /// assert_eq!(t.motion(50), 0.0);
    /// ```
    pub fn motion(&self, frame: usize) -> f64 {
        let t = frame as f64;
        if frame <= self.onset || frame >= self.offset_end {
            0.0
        } else if frame < self.apex_start {
            (t - self.onset as f64) / (self.apex_start - self.onset) as f64
        } else if frame <= self.apex_end {
            1.0
        } else {
            (self.offset_end as f64 - t) / (self.offset_end - self.apex_end) as f64
        }
    }
}

/// Eq. 4.3: `s_i = (clip((m_i − μ_e)/σ_e) + 1) / 2`, the apex label of a sequence whose mean
/// absolute deformation is `m_i`, for an expression with deformation mean `μ_e` and standard
/// deviation `σ_e` over the dataset; clip to `[−1, 1]`. `σ_e = 0` gives 0.5.
///
/// ```
/// use meshgnn_data::intensity_scale;
/// assert_eq!(intensity_scale(2.0, 2.0, 1.0), 0.5);
/// assert_eq!(intensity_scale(2.5, 2.0, 1.0), 0.75);
/// assert_eq!(intensity_scale(9.0, 2.0, 1.0), 1.0);
/// assert_eq!(intensity_scale(-9.0, 2.0, 1.0), 0.0);
/// ```
pub fn intensity_scale(m_i: f64, mu_e: f64, sigma_e: f64) -> f64 {
    if sigma_e <= 0.0 || !sigma_e.is_finite() {
        return 0.5;
    }
    (((m_i - mu_e) / sigma_e).clamp(-1.0, 1.0) + 1.0) / 2.0
}

/// The intensity scales `s_i` of eq. 4.3 for `sequences: (expression, m_i)`, with `μ_e`, `σ_e`
/// (population standard deviation) computed per expression over the given sequences.
///
/// ```
/// use meshgnn_data::{Expression, intensity_scales};
/// let s = intensity_scales(&[(Expression::Happy, 1.0), (Expression::Happy, 3.0), (Expression::Sad, 5.0)]);
/// assert_eq!(s, vec![0.0, 1.0, 0.5]);
/// ```
pub fn intensity_scales(sequences: &[(Expression, f64)]) -> Vec<f64> {
    let mut stats = [(0.0f64, 0.0f64, 0usize); 6];
    for &(e, m) in sequences {
        let s = &mut stats[e.index()];
        s.0 += m;
        s.1 += m * m;
        s.2 += 1;
    }
    sequences
        .iter()
        .map(|&(e, m)| {
            let (sum, sq, n) = stats[e.index()];
            let n = n.max(1) as f64;
            let mu = sum / n;
            let sigma = (sq / n - mu * mu).max(0.0).sqrt();
            intensity_scale(m, mu, sigma)
        })
        .collect()
}

/// One generated expression sequence (frames subsampled by `frame_step`).
#[derive(Debug, Clone, PartialEq)]
pub struct FaceSequence {
    /// The expression.
    pub expression: Expression,
    /// Subject-dependent timing.
    pub timing: SequenceTiming,
    /// Subject's extremeness in `[0.35, 1]` (scales the actions at the apex, on top of the
    /// subject's [`ExpressionStyle`]).
    pub extremeness: f64,
    /// Indices of the frames kept.
    pub frame_indices: Vec<usize>,
    /// Motion value of each kept frame, `[0, 1]`.
    pub motion: Vec<f64>,
    /// Vertices of each kept frame, `#kept × #V×3`.
    pub frames: Vec<Vec<[f32; 3]>>,
    /// `m_i` of eq. 4.3: mean over kept frames and vertices of `|v_t − v_neutral|` (mm).
    pub mean_abs_deformation: f64,
}

/// One subject: identity, neutral face and the six sequences.
#[derive(Debug, Clone, PartialEq)]
pub struct FaceSubject {
    /// `face_007`.
    pub name: String,
    /// Identity parameters.
    pub identity: FaceIdentity,
    /// Neutral face `#V×3`.
    pub neutral: Vec<[f32; 3]>,
    /// One sequence per expression, in [`Expression::ALL`] order.
    pub sequences: Vec<FaceSequence>,
    /// `train` or `test`.
    pub split: &'static str,
}

/// How to generate the face set.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FaceSetConfig {
    /// Number of subjects (180 in 4DFAB).
    pub subjects: usize,
    /// Seed of every random choice.
    pub seed: u64,
    /// Keep every `frame_step`-th frame (the thesis samples every ≈5 frames).
    pub frame_step: usize,
}

impl Default for FaceSetConfig {
    fn default() -> Self {
        Self {
            subjects: 180,
            seed: 0,
            frame_step: 5,
        }
    }
}

impl FaceSetConfig {
    /// Number of test subjects: 27 of 180 as in the thesis, proportionally otherwise.
    pub fn test_subjects(&self) -> usize {
        (self.subjects * 27)
            .div_ceil(180)
            .min(self.subjects.saturating_sub(1))
    }

    /// The expression style of subject `index`: its own seeded stream, independent of the
    /// identity and timing draws, so it is the same whatever the frame step.
    ///
    /// ```
    /// use meshgnn_data::FaceSetConfig;
    /// let cfg = FaceSetConfig::default();
    /// assert_eq!(cfg.style(7), cfg.style(7));
    /// assert_ne!(cfg.style(7), cfg.style(8));
    /// ```
    pub fn style(&self, index: usize) -> ExpressionStyle {
        ExpressionStyle::random(item_seed(item_seed(self.seed, index as u64), STYLE_STREAM))
    }

    /// Subject `index` (test subjects are the last [`FaceSetConfig::test_subjects`]). Frame
    /// `t` of a sequence is the neutral face deformed by
    /// [`ExpressionStyle::actions_at`]`(apex, motion_t)` with `apex` = the expression's
    /// actions × the subject's overall scale (0.85-1.15) × the sequence's extremeness.
    ///
    /// ```
    /// use meshgnn_data::{FaceSetConfig, FaceTemplate};
    /// let cfg = FaceSetConfig { subjects: 10, frame_step: 20, ..Default::default() };
    /// let t = FaceTemplate::new(32, 30)?;
    /// let s = cfg.subject(&t, 9)?;
    /// assert_eq!((s.split, s.sequences.len()), ("test", 6));
    /// assert_eq!(s, cfg.subject(&t, 9)?);
    /// # Ok::<(), meshgnn_data::Error>(())
    /// ```
    pub fn subject(&self, template: &FaceTemplate, index: usize) -> Result<FaceSubject> {
        if self.frame_step == 0 {
            return Err(invalid("frame_step", 0, "must be at least 1"));
        }
        if index >= self.subjects {
            return Err(invalid("index", index, "must be below the subject count"));
        }
        let mut rng = StdRng::seed_from_u64(item_seed(self.seed, index as u64));
        let identity = FaceIdentity::random(rng.random());
        let neutral = template.neutral(&identity);
        let scale: f64 = rng.random_range(0.85..1.15);
        let style = self.style(index);
        let sequences = Expression::ALL
            .iter()
            .map(|&expression| {
                let timing = SequenceTiming::random(rng.random());
                let extremeness = rng.random_range(0.35..1.0);
                let apex = expression.actions().scaled(scale * extremeness);
                let frame_indices: Vec<usize> =
                    (0..timing.frames).step_by(self.frame_step).collect();
                let motion: Vec<f64> = frame_indices.iter().map(|&f| timing.motion(f)).collect();
                let frames: Vec<Vec<[f32; 3]>> = motion
                    .iter()
                    .map(|&m| {
                        apply_styled_actions(
                            template,
                            &neutral,
                            &style.actions_at(&apex, m),
                            &style,
                        )
                    })
                    .collect();
                let mut total = 0.0;
                for frame in &frames {
                    for (p, q) in frame.iter().zip(&neutral) {
                        let d = [0, 1, 2].map(|k| f64::from(p[k]) - f64::from(q[k]));
                        total += (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                    }
                }
                let count = (frames.len() * neutral.len()).max(1) as f64;
                FaceSequence {
                    expression,
                    timing,
                    extremeness,
                    frame_indices,
                    motion,
                    frames,
                    mean_abs_deformation: total / count,
                }
            })
            .collect();
        Ok(FaceSubject {
            name: format!("face_{index:03}"),
            identity,
            neutral,
            sequences,
            split: if index + self.test_subjects() >= self.subjects {
                "test"
            } else {
                "train"
            },
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_follow_motion_and_extremeness() {
        let cfg = FaceSetConfig {
            subjects: 6,
            frame_step: 5,
            ..Default::default()
        };
        let t = FaceTemplate::new(40, 40).unwrap();
        let subjects: Vec<FaceSubject> = (0..6).map(|i| cfg.subject(&t, i).unwrap()).collect();
        // More extreme sequences of one expression deform more (m_i grows with extremeness).
        let mut happy: Vec<(f64, f64)> = subjects
            .iter()
            .map(|s| {
                (
                    s.sequences[0].extremeness,
                    s.sequences[0].mean_abs_deformation,
                )
            })
            .collect();
        happy.sort_by(|a, b| a.0.total_cmp(&b.0));
        assert!(happy[0].1 < happy[5].1);
        // First and last kept frames are neutral.
        for s in &subjects {
            for q in &s.sequences {
                assert_eq!(q.motion[0], 0.0);
                assert_eq!(q.frames[0], s.neutral);
            }
        }
        assert_eq!(FaceSetConfig::default().test_subjects(), 27);
    }
}
