//! The per-frame expression labels of a 4D face dataset (thesis eq. 4.3): frame `t` of a
//! sequence of expression `e` is labelled `y = motion_t · s_i · onehot(e)`, where `s_i` is the
//! sequence's intensity scale ([`intensity_scales`] over every sequence of the dataset, per
//! expression) and `motion_t ∈ [0, 1]` its position on the onset-apex-offset curve.

use std::collections::BTreeMap;

use crate::{Error, Expression, Result, intensity_scales};

/// What the labels of one sequence need from it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SequenceStats {
    /// The sequence's expression.
    pub expression: Expression,
    /// `m_i` of eq. 4.3 (mm).
    pub mean_abs_deformation: f64,
    /// The subject's extremeness of the expression.
    pub extremeness: f64,
}

/// The label of one frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameLabel {
    /// `s_i` of the frame's sequence.
    pub intensity: f64,
    /// `motion · s_i` at the expression's index, 0 elsewhere.
    pub label: [f64; 6],
    /// `m_i` of the frame's sequence (mm).
    pub mean_abs_deformation: f64,
    /// The subject's extremeness of the expression.
    pub extremeness: f64,
}

/// The intensity scale and statistics of every sequence, by subject and expression.
#[derive(Debug, Clone, PartialEq)]
pub struct ExpressionLabels {
    subjects: Vec<BTreeMap<Expression, (f64, SequenceStats)>>,
}

impl ExpressionLabels {
    /// Eq. 4.3's scales of `subjects[s]` = the sequences of subject `s`, with `μ_e` and `σ_e`
    /// over all of them. A subject with two sequences of one expression is refused: a frame
    /// could not tell which one it belongs to.
    ///
    /// ```
    /// use meshgnn_data::{Expression, ExpressionLabels, SequenceStats};
    /// let seq = |m| SequenceStats { expression: Expression::Happy, mean_abs_deformation: m, extremeness: 1.0 };
    /// let labels = ExpressionLabels::new(&[vec![seq(1.0)], vec![seq(3.0)]])?;
    /// let frame = labels.label(1, Expression::Happy, 0.5)?;
    /// assert_eq!(frame.intensity, 1.0); // one σ above the mean
    /// assert_eq!(frame.label[Expression::Happy.index()], 0.5);
    /// assert!(labels.label(0, Expression::Sad, 1.0).is_err()); // subject 0 has no sad sequence
    /// # Ok::<(), meshgnn_data::Error>(())
    /// ```
    pub fn new(subjects: &[Vec<SequenceStats>]) -> Result<Self> {
        let all: Vec<(Expression, f64)> = subjects
            .iter()
            .flatten()
            .map(|s| (s.expression, s.mean_abs_deformation))
            .collect();
        let mut scales = intensity_scales(&all).into_iter();
        let mut out = Vec::with_capacity(subjects.len());
        for (subject, sequences) in subjects.iter().enumerate() {
            let mut by_expression = BTreeMap::new();
            // one scale per sequence, in the order of `all`
            for (s, scale) in sequences.iter().zip(&mut scales) {
                if by_expression.insert(s.expression, (scale, *s)).is_some() {
                    return Err(Error::Topology {
                        element: format!("subject {subject}"),
                        message: format!("has two {} sequences", s.expression.name()),
                    });
                }
            }
            out.push(by_expression);
        }
        Ok(Self { subjects: out })
    }

    /// The label of a frame of `subject`'s `expression` sequence at `motion`. Errors when the
    /// subject has no such sequence.
    pub fn label(&self, subject: usize, expression: Expression, motion: f64) -> Result<FrameLabel> {
        let (intensity, stats) = self
            .subjects
            .get(subject)
            .and_then(|s| s.get(&expression))
            .copied()
            .ok_or_else(|| Error::Topology {
                element: format!("subject {subject}"),
                message: format!("has no {} sequence to label", expression.name()),
            })?;
        let mut label = [0.0f64; 6];
        label[expression.index()] = motion * intensity;
        Ok(FrameLabel {
            intensity,
            label,
            mean_abs_deformation: stats.mean_abs_deformation,
            extremeness: stats.extremeness,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seq(expression: Expression, m: f64) -> SequenceStats {
        SequenceStats {
            expression,
            mean_abs_deformation: m,
            extremeness: m / 10.0,
        }
    }

    #[test]
    fn scales_are_per_expression_over_all_subjects() {
        // happy: m = 1, 3 → μ = 2, σ = 1 → s = 0, 1; sad: one sequence → σ = 0 → s = 0.5
        let labels = ExpressionLabels::new(&[
            vec![seq(Expression::Happy, 1.0), seq(Expression::Sad, 7.0)],
            vec![seq(Expression::Happy, 3.0)],
        ])
        .unwrap();
        let a = labels.label(0, Expression::Happy, 1.0).unwrap();
        assert_eq!(
            (a.intensity, a.label[Expression::Happy.index()]),
            (0.0, 0.0)
        );
        let b = labels.label(1, Expression::Happy, 0.4).unwrap();
        assert_eq!(b.intensity, 1.0);
        assert_eq!(b.label[Expression::Happy.index()], 0.4);
        assert_eq!(b.label.iter().filter(|&&x| x != 0.0).count(), 1);
        let c = labels.label(0, Expression::Sad, 1.0).unwrap();
        assert_eq!(
            (c.intensity, c.mean_abs_deformation, c.extremeness),
            (0.5, 7.0, 0.7)
        );
    }

    #[test]
    fn a_missing_or_doubled_sequence_is_an_error() {
        let labels = ExpressionLabels::new(&[vec![seq(Expression::Happy, 1.0)]]).unwrap();
        let err = labels
            .label(0, Expression::Sad, 1.0)
            .unwrap_err()
            .to_string();
        assert!(err.contains("subject 0") && err.contains("sad"), "{err}");
        assert!(labels.label(1, Expression::Happy, 1.0).is_err());
        let doubled = vec![seq(Expression::Happy, 1.0), seq(Expression::Happy, 2.0)];
        assert!(ExpressionLabels::new(&[doubled]).is_err());
    }
}
