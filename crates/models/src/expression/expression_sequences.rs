//! The training and evaluation data of the expression generator (thesis ch. 4.4.1): subjects'
//! neutral faces and their expression sequences, each frame with its eq. 4.3 label, all
//! registered to one template.

use crate::{Error, Result};

/// One expression sequence of one subject.
#[derive(Debug, Clone, PartialEq)]
pub struct ExpressionSequence {
    /// Index of the subject's neutral face in [`ExpressionSequences::neutrals`].
    pub subject: usize,
    /// The expression's label channel (0..6, in the order of the label signal).
    pub expression: usize,
    /// Eq. 4.3 label of every frame: one-hot × motion × intensity, `#T×6`.
    pub labels: Vec<[f32; 6]>,
    /// The frames' vertices, `#T × (#V×3)`.
    pub frames: Vec<Vec<[f32; 3]>>,
}

/// Neutral faces and the sequences that deform them.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ExpressionSequences {
    /// One neutral face per subject, `#S × (#V×3)`.
    pub neutrals: Vec<Vec<[f32; 3]>>,
    /// The sequences.
    pub sequences: Vec<ExpressionSequence>,
}

impl ExpressionSequences {
    /// Checks every face has `vertices` finite vertices, every sequence has as many labels as
    /// frames (at least one), a known subject and expression, and labels in `[0, 1]`.
    pub fn check(&self, what: &str, vertices: usize) -> Result<()> {
        let bad = |reason: String| {
            Err(Error::Invalid {
                what: what.into(),
                reason,
            })
        };
        let face_ok =
            |f: &Vec<[f32; 3]>| f.len() == vertices && f.iter().flatten().all(|c| c.is_finite());
        if let Some(s) = self.neutrals.iter().position(|f| !face_ok(f)) {
            return bad(format!(
                "neutral face {s}: needs {vertices} finite vertices (the template's)"
            ));
        }
        for (i, q) in self.sequences.iter().enumerate() {
            if q.subject >= self.neutrals.len() || q.expression >= 6 {
                return bad(format!(
                    "sequence {i}: subject {} of {}, expression {} of 6",
                    q.subject,
                    self.neutrals.len(),
                    q.expression
                ));
            }
            if q.frames.is_empty() || q.frames.len() != q.labels.len() {
                return bad(format!(
                    "sequence {i}: {} frames and {} labels",
                    q.frames.len(),
                    q.labels.len()
                ));
            }
            if let Some(t) = q.frames.iter().position(|f| !face_ok(f)) {
                return bad(format!(
                    "sequence {i}, frame {t}: needs {vertices} finite vertices"
                ));
            }
            if q.labels.iter().flatten().any(|l| !(0.0..=1.0).contains(l)) {
                return bad(format!("sequence {i}: a label outside [0, 1]"));
            }
        }
        Ok(())
    }

    /// Splits off the last `count` subjects (with their sequences, subject indices
    /// renumbered): `(kept, held out)`, subject-disjoint.
    ///
    /// ```
    /// use meshgnn_models::expression::{ExpressionSequence, ExpressionSequences};
    /// let q = |subject| ExpressionSequence { subject, expression: 0, labels: vec![[0.0; 6]], frames: vec![vec![[0.0; 3]]] };
    /// let data = ExpressionSequences { neutrals: vec![vec![[0.0; 3]]; 3], sequences: vec![q(0), q(2), q(1)] };
    /// let (kept, held) = data.hold_out_subjects(1);
    /// assert_eq!((kept.neutrals.len(), kept.sequences.len()), (2, 2));
    /// assert_eq!((held.neutrals.len(), held.sequences[0].subject), (1, 0));
    /// ```
    pub fn hold_out_subjects(&self, count: usize) -> (Self, Self) {
        let first = self.neutrals.len().saturating_sub(count);
        let part = |range: std::ops::Range<usize>| Self {
            neutrals: self.neutrals[range.clone()].to_vec(),
            sequences: self
                .sequences
                .iter()
                .filter(|q| range.contains(&q.subject))
                .map(|q| ExpressionSequence {
                    subject: q.subject - range.start,
                    ..q.clone()
                })
                .collect(),
        };
        (part(0..first), part(first..self.neutrals.len()))
    }

    /// Number of frames over all sequences.
    pub fn frame_count(&self) -> usize {
        self.sequences.iter().map(|q| q.frames.len()).sum()
    }

    /// Every frame's displacement from its subject's neutral face, `#frames × (#V×3)`.
    pub fn displacements(&self) -> Vec<Vec<[f32; 3]>> {
        let mut out = Vec::with_capacity(self.frame_count());
        for q in &self.sequences {
            let Some(neutral) = self.neutrals.get(q.subject) else {
                continue;
            };
            for frame in &q.frames {
                out.push(
                    frame
                        .iter()
                        .zip(neutral)
                        .map(|(p, n)| [p[0] - n[0], p[1] - n[1], p[2] - n[2]])
                        .collect(),
                );
            }
        }
        out
    }

    /// Root mean square of the displacement coordinates (data units); 0 when empty.
    ///
    /// ```
    /// use meshgnn_models::expression::{ExpressionSequence, ExpressionSequences};
    /// let data = ExpressionSequences {
    ///     neutrals: vec![vec![[0.0; 3]]],
    ///     sequences: vec![ExpressionSequence { subject: 0, expression: 0,
    ///         labels: vec![[0.0; 6]], frames: vec![vec![[3.0, 0.0, 0.0]]] }],
    /// };
    /// assert!((data.displacement_rms() - 3.0f64.sqrt()).abs() < 1e-9);
    /// ```
    pub fn displacement_rms(&self) -> f64 {
        let (mut sum, mut count) = (0.0f64, 0usize);
        for d in self.displacements() {
            for c in d.iter().flatten() {
                sum += f64::from(*c).powi(2);
                count += 1;
            }
        }
        if count == 0 {
            0.0
        } else {
            (sum / count as f64).sqrt()
        }
    }
}
