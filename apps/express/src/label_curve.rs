//! The label signals `express generate` animates: the onset-apex-offset curve of thesis
//! ch. 4.4.1 (Fig. 4.2) for one expression, or any curve a user draws as a CSV of keys
//! `frame,expression,amplitude`.
//!
//! # CSV curves
//! One key per line (an optional header line `frame,expression,amplitude`, blank lines and
//! `#` comments are skipped). Each expression's amplitude is linear between its keys and held
//! at its first and last key outside them; expressions without keys stay 0; the animation has
//! `last key frame + 1` frames. Several expressions may have keys (mixed expressions, beyond
//! the thesis, which labels one expression per sequence).

use std::path::Path;

use anyhow::{Result, bail};
use meshgnn_data::{Expression, SequenceTiming};

/// Most frames of one animation.
pub const MAX_FRAMES: usize = 10_000;

/// The expression called `name` (`happy`, `sad`, ...).
pub fn expression_named(name: &str) -> Result<Expression> {
    Expression::ALL
        .iter()
        .copied()
        .find(|e| e.name() == name)
        .ok_or_else(|| {
            let names: Vec<&str> = Expression::ALL.iter().map(|e| e.name()).collect();
            anyhow::anyhow!("unknown expression `{name}` (one of {})", names.join(", "))
        })
}

/// Eq. 4.3's labels of one sequence: `expression`'s channel follows `timing`'s motion scaled
/// by `intensity ∈ [0, 1]`.
pub fn timed_labels(
    expression: Expression,
    timing: &SequenceTiming,
    intensity: f64,
) -> Result<Vec<[f32; 6]>> {
    if !(0.0..=1.0).contains(&intensity) {
        bail!("--intensity {intensity}: must be in [0, 1]");
    }
    let t = timing;
    if t.frames == 0 || t.frames > MAX_FRAMES {
        bail!("--frames {}: must be in 1..={MAX_FRAMES}", t.frames);
    }
    if !(t.onset < t.apex_start && t.apex_start <= t.apex_end && t.apex_end < t.offset_end) {
        bail!(
            "timing onset {} < apex {}:{} < offset {}: the frames must increase \
             (onset < apex start <= apex end < offset)",
            t.onset,
            t.apex_start,
            t.apex_end,
            t.offset_end
        );
    }
    if t.offset_end >= t.frames {
        bail!(
            "--offset {}: must be before the last frame ({} frames)",
            t.offset_end,
            t.frames
        );
    }
    Ok((0..t.frames)
        .map(|f| {
            let mut label = [0.0f32; 6];
            label[expression.index()] = (t.motion(f) * intensity) as f32;
            label
        })
        .collect())
}

/// The labels of the CSV curve `text` read from `path` (module docs); errors name the file,
/// the line and the problem.
pub fn parse_label_curve(text: &str, path: &Path) -> Result<Vec<[f32; 6]>> {
    let mut keys: [Vec<(usize, f32)>; 6] = Default::default();
    let mut last = None;
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        let bad = |what: String| anyhow::anyhow!("{}:{}: {what}", path.display(), n + 1);
        if line.is_empty() || line.starts_with('#') || (n == 0 && line.starts_with("frame")) {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let [frame, expression, amplitude] = fields[..] else {
            return Err(bad(format!(
                "`{line}`: expected `frame,expression,amplitude`"
            )));
        };
        let frame: usize = frame
            .parse()
            .map_err(|_| bad(format!("frame `{frame}` is not a whole number >= 0")))?;
        if frame >= MAX_FRAMES {
            return Err(bad(format!("frame {frame}: at most {} frames", MAX_FRAMES)));
        }
        let expression = expression_named(expression).map_err(|e| bad(e.to_string()))?;
        let amplitude: f32 = amplitude
            .parse()
            .map_err(|_| bad(format!("amplitude `{amplitude}` is not a number")))?;
        if !(0.0..=1.0).contains(&amplitude) {
            return Err(bad(format!("amplitude {amplitude} is outside [0, 1]")));
        }
        let channel = &mut keys[expression.index()];
        if channel.iter().any(|k| k.0 == frame) {
            return Err(bad(format!(
                "a second key for {} at frame {frame}",
                expression.name()
            )));
        }
        channel.push((frame, amplitude));
        last = last.max(Some(frame));
    }
    let Some(last) = last else {
        bail!(
            "{}: no keys (lines `frame,expression,amplitude`)",
            path.display()
        );
    };
    for channel in &mut keys {
        channel.sort_by_key(|k| k.0);
    }
    Ok((0..=last)
        .map(|f| {
            let mut label = [0.0f32; 6];
            for (value, channel) in label.iter_mut().zip(&keys) {
                *value = interpolate(channel, f);
            }
            label
        })
        .collect())
}

/// The piecewise-linear value of sorted `keys` at `frame`, held outside them (0 without keys).
fn interpolate(keys: &[(usize, f32)], frame: usize) -> f32 {
    let after = keys.partition_point(|k| k.0 <= frame);
    match (
        after.checked_sub(1).and_then(|i| keys.get(i)),
        keys.get(after),
    ) {
        (Some(&(f0, a0)), Some(&(f1, a1))) => {
            let w = (frame - f0) as f32 / (f1 - f0) as f32;
            a0 + w * (a1 - a0)
        }
        (Some(&(_, a)), None) | (None, Some(&(_, a))) => a,
        (None, None) => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn parse(text: &str) -> Result<Vec<[f32; 6]>> {
        parse_label_curve(text, Path::new("curve.csv"))
    }

    #[test]
    fn keys_are_interpolated_held_and_mixed() {
        let labels =
            parse("frame,expression,amplitude\n0,happy,0\n10,happy,1\n# a comment\n\n5,sad,0.4\n20,sad,0\n")
                .unwrap();
        assert_eq!(labels.len(), 21);
        let happy = Expression::Happy.index();
        let sad = Expression::Sad.index();
        assert_eq!(labels[5][happy], 0.5);
        assert_eq!(labels[15][happy], 1.0); // held after the last key
        assert_eq!(labels[2][sad], 0.4); // held before the first key
        assert!((labels[10][sad] - 0.4 * 10.0 / 15.0).abs() < 1e-6);
        assert_eq!(labels[20][sad], 0.0);
        assert!(labels.iter().all(|l| l[Expression::Fear.index()] == 0.0));
    }

    #[test]
    fn bad_curves_name_the_file_line_and_problem() {
        for (text, needle) in [
            ("0,smirk,1", "curve.csv:1: unknown expression `smirk`"),
            ("0,happy,0\n-3,happy,1", "curve.csv:2: frame `-3`"),
            ("0,happy,1.5", "outside [0, 1]"),
            ("0,happy,x", "amplitude `x`"),
            ("0,happy", "expected `frame,expression,amplitude`"),
            ("0,happy,1\n0,happy,0", "a second key for happy at frame 0"),
            ("99999999,happy,1", "at most 10000 frames"),
            ("# nothing\n", "no keys"),
        ] {
            let err = parse(text).unwrap_err().to_string();
            assert!(err.contains(needle), "{text:?}: {err}");
        }
    }

    #[test]
    fn timed_labels_follow_onset_apex_offset() {
        let timing = SequenceTiming {
            frames: 60,
            onset: 10,
            apex_start: 20,
            apex_end: 40,
            offset_end: 50,
        };
        let labels = timed_labels(Expression::Surprise, &timing, 0.8).unwrap();
        let c = Expression::Surprise.index();
        assert_eq!(labels.len(), 60);
        assert_eq!(
            (labels[5][c], labels[30][c], labels[55][c]),
            (0.0, 0.8, 0.0)
        );
        assert!((labels[15][c] - 0.4).abs() < 1e-6);
        assert!(timed_labels(Expression::Sad, &timing, 1.5).is_err());
        let late = SequenceTiming {
            offset_end: 60,
            ..timing
        };
        assert!(timed_labels(Expression::Sad, &late, 0.5).is_err());
        let backwards = SequenceTiming {
            apex_start: 5,
            ..timing
        };
        assert!(timed_labels(Expression::Sad, &backwards, 0.5).is_err());
    }

    proptest! {
        #[test]
        fn any_text_gives_labels_in_range_or_an_error(text in "[0-9a-z,.\\-#\\n ]{0,200}") {
            if let Ok(labels) = parse(&text) {
                prop_assert!(!labels.is_empty() && labels.len() <= MAX_FRAMES);
                prop_assert!(labels.iter().flatten().all(|v| (0.0..=1.0).contains(v)));
            }
        }

        #[test]
        fn valid_keys_round_trip(keys in proptest::collection::btree_map(0usize..500, 0u32..=100, 1..20)) {
            let text: String = keys.iter().map(|(f, a)| format!("{f},fear,{}\n", *a as f32 / 100.0)).collect();
            let labels = parse(&text).unwrap();
            let c = Expression::Fear.index();
            for (f, a) in &keys {
                prop_assert!((labels[*f][c] - *a as f32 / 100.0).abs() < 1e-6);
            }
        }
    }
}
