//! Reads a 4D face folder dataset (`synth faces` output, or any folder with the same manifest
//! labels) into the expression model's sequences: every file labelled with a `subject`, an
//! `expression` and a `frame` is a frame of that subject's sequence of that expression; the
//! file labelled `"expression": "neutral"` is the subject's neutral face.

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{Context, Result, bail};
use meshgnn_data::{Expression, FolderDataset};
use meshgnn_geometry::TriMesh;
use meshgnn_models::expression::{ExpressionSequence, ExpressionSequences};
use rayon::prelude::*;
use serde_json::Value;

/// The frames of one split, with the template they are registered to.
pub struct FaceFolder {
    /// The dataset's template (the mean face).
    pub template: TriMesh,
    /// The split's subjects and sequences.
    pub sequences: ExpressionSequences,
    /// Distinct subjects of the split.
    pub subjects: usize,
}

/// What the manifest says about one frame file.
struct FrameEntry {
    subject: u64,
    expression: Option<usize>,
    frame: u64,
    label: [f32; 6],
}

fn entry(name: &str, label: &Value) -> Result<FrameEntry> {
    let bad = |what: &str| anyhow::anyhow!("manifest label of `{name}`: {what}");
    let subject = label["subject"]
        .as_u64()
        .ok_or_else(|| bad("no `subject` number"))?;
    let expression = match label["expression"].as_str() {
        Some("neutral") => None,
        Some(e) => Some(
            Expression::ALL
                .iter()
                .position(|x| x.name() == e)
                .ok_or_else(|| bad(&format!("unknown expression `{e}`")))?,
        ),
        None => return Err(bad("no `expression` name")),
    };
    let mut values = [0.0f32; 6];
    if expression.is_some() {
        let list = label["label"]
            .as_array()
            .ok_or_else(|| bad("no `label` list"))?;
        if list.len() != 6 {
            return Err(bad("`label` must have 6 entries"));
        }
        for (v, x) in values.iter_mut().zip(list) {
            *v = x
                .as_f64()
                .ok_or_else(|| bad("`label` entries must be numbers"))? as f32;
        }
    }
    Ok(FrameEntry {
        subject,
        expression,
        frame: label["frame"].as_u64().unwrap_or(0),
        label: values,
    })
}

/// A frame's number, label and vertices.
type LabelledFrame = (u64, [f32; 6], Vec<[f32; 3]>);

/// Reads split `split` of the dataset in `dir`.
pub fn read_face_folder(dir: &Path, split: &str) -> Result<FaceFolder> {
    let data =
        FolderDataset::open(dir).with_context(|| format!("opening dataset {}", dir.display()))?;
    let template = data.template().cloned().with_context(|| {
        format!(
            "{}: the manifest names no template; express needs faces registered to one",
            dir.display()
        )
    })?;
    let names = data.split(split)?;
    let entries = names
        .iter()
        .map(|name| {
            let label = data.manifest().labels.get(name).with_context(|| {
                format!("{}: `{name}` has no label in the manifest", dir.display())
            })?;
            entry(name, label)
        })
        .collect::<Result<Vec<_>>>()?;
    let vertices = names
        .par_iter()
        .map(|name| Ok(data.load(name)?.vertices().to_vec()))
        .collect::<Result<Vec<_>>>()?;
    let mut subjects: BTreeMap<u64, usize> = BTreeMap::new();
    for e in &entries {
        let next = subjects.len();
        subjects.entry(e.subject).or_insert(next);
    }
    let mut neutrals: Vec<Option<Vec<[f32; 3]>>> = vec![None; subjects.len()];
    let mut frames: BTreeMap<(usize, usize), Vec<LabelledFrame>> = BTreeMap::new();
    for (e, v) in entries.into_iter().zip(vertices) {
        let s = subjects[&e.subject];
        match e.expression {
            None => neutrals[s] = Some(v),
            Some(x) => frames
                .entry((s, x))
                .or_default()
                .push((e.frame, e.label, v)),
        }
    }
    let neutrals = neutrals
        .into_iter()
        .zip(subjects.keys())
        .map(|(n, id)| {
            n.with_context(|| {
                format!(
                    "{}: subject {id} of split `{split}` has no neutral face",
                    dir.display()
                )
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let sequences = frames
        .into_iter()
        .map(|((subject, expression), mut list)| {
            list.sort_by_key(|f| f.0);
            ExpressionSequence {
                subject,
                expression,
                labels: list.iter().map(|f| f.1).collect(),
                frames: list.into_iter().map(|f| f.2).collect(),
            }
        })
        .collect::<Vec<_>>();
    if sequences.is_empty() {
        bail!(
            "{}: split `{split}` has no expression frames",
            dir.display()
        );
    }
    let sequences = ExpressionSequences {
        neutrals,
        sequences,
    };
    sequences.check(
        &format!("{} split `{split}`", dir.display()),
        template.vertex_count(),
    )?;
    Ok(FaceFolder {
        template,
        subjects: subjects.len(),
        sequences,
    })
}
