//! End-to-end tests of `express`: the binary run as a user runs it, on a tiny 4D face dataset
//! (a 56 × 50 template, 4 subjects, every 20th frame) written to a temporary folder, with
//! models trained on it for one epoch.
#![allow(clippy::expect_used, clippy::unwrap_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

use meshgnn_data::{
    ExpressionLabels, FaceIdentity, FaceSetConfig, FaceTemplate, Manifest, SequenceStats,
    write_dataset,
};
use meshgnn_geometry::{TriMesh, icosphere, read_mesh, read_morph_animation, write_mesh};
use serde_json::{Value, json};

fn express(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_express"))
        .args(args)
        .output()
        .expect("the binary runs")
}

fn ok(out: &Output) -> String {
    assert!(
        out.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn fails(out: &Output) -> String {
    assert!(!out.status.success(), "expected a failure");
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(err.trim().lines().count(), 1, "one line: {err}");
    err
}

struct Fixture {
    _dir: tempfile::TempDir,
    data: PathBuf,
    generator: PathBuf,
    baseline: PathBuf,
}

/// A `synth faces`-like folder: neutral + every 20th frame of six sequences per subject.
fn write_faces(root: &Path) {
    let cfg = FaceSetConfig {
        subjects: 4,
        seed: 5,
        frame_step: 20,
    };
    let template = FaceTemplate::new(56, 50).unwrap();
    let triangles = template.triangles().to_vec();
    let subjects: Vec<_> = (0..4).map(|i| cfg.subject(&template, i).unwrap()).collect();
    let labels = ExpressionLabels::new(
        &subjects
            .iter()
            .map(|s| {
                s.sequences
                    .iter()
                    .map(|q| SequenceStats {
                        expression: q.expression,
                        mean_abs_deformation: q.mean_abs_deformation,
                        extremeness: q.extremeness,
                    })
                    .collect::<Vec<_>>()
            })
            .collect::<Vec<_>>(),
    )
    .unwrap();
    let mut manifest = Manifest {
        format_version: 1,
        description: "test faces".into(),
        template: Some("template.ply".into()),
        splits: Default::default(),
        labels: Default::default(),
    };
    let mut files = Vec::new();
    for (i, s) in subjects.iter().enumerate() {
        let neutral = format!("{}_neutral.ply", s.name);
        let mut names = vec![neutral.clone()];
        manifest.labels.insert(
            neutral.clone(),
            json!({"subject": i, "expression": "neutral"}),
        );
        files.push((
            neutral,
            TriMesh::new(s.neutral.clone(), triangles.clone()).unwrap(),
        ));
        for q in &s.sequences {
            for ((frame, v), motion) in q.frame_indices.iter().zip(&q.frames).zip(&q.motion) {
                let name = format!("{}_{}_f{frame:03}.ply", s.name, q.expression.name());
                let l = labels.label(i, q.expression, *motion).unwrap();
                manifest.labels.insert(
                    name.clone(),
                    json!({"subject": i, "expression": q.expression.name(), "frame": frame, "label": l.label}),
                );
                files.push((
                    name.clone(),
                    TriMesh::new(v.clone(), triangles.clone()).unwrap(),
                ));
                names.push(name);
            }
        }
        manifest
            .splits
            .entry(s.split.to_string())
            .or_default()
            .extend(names);
    }
    let mean = TriMesh::new(template.neutral(&FaceIdentity::mean()), triangles).unwrap();
    write_dataset(root, &manifest, Some(&mean), &files).unwrap();
}

fn fixture() -> &'static Fixture {
    static FIXTURE: OnceLock<Fixture> = OnceLock::new();
    FIXTURE.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let data = dir.path().join("faces");
        write_faces(&data);
        let generator = dir.path().join("generator.safetensors");
        let baseline = dir.path().join("baseline.safetensors");
        for (decoder, out) in [("spiral", &generator), ("blendshape", &baseline)] {
            ok(&express(&[
                "train",
                data.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
                "--decoder",
                decoder,
                "--epochs",
                "1",
                "--validation-subjects",
                "1",
            ]));
        }
        Fixture {
            _dir: dir,
            data,
            generator,
            baseline,
        }
    })
}

#[test]
fn eval_prints_table_4_2_keys() {
    let f = fixture();
    let out = ok(&express(&[
        "eval",
        f.data.to_str().unwrap(),
        "--weights",
        f.generator.to_str().unwrap(),
        "--baseline",
        f.baseline.to_str().unwrap(),
        "--json",
    ]));
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["test_subjects"], 1);
    assert_eq!(v["per_expression_mm"].as_object().unwrap().len(), 6);
    for key in [
        "total_mm",
        "blendshape_total_mm",
        "jitter_mm",
        "truth_jitter_mm",
    ] {
        assert!(v[key].as_f64().unwrap() >= 0.0, "{key}");
    }
}

#[test]
fn generate_writes_a_glb_animation_and_frames_that_read_back() {
    let f = fixture();
    let dir = tempfile::tempdir().unwrap();
    let glb = dir.path().join("anim.glb");
    let sheet = dir.path().join("sheet.png");
    let neutral = f.data.join("face_000_neutral.ply");
    let out = ok(&express(&[
        "generate",
        neutral.to_str().unwrap(),
        "-o",
        glb.to_str().unwrap(),
        "--weights",
        f.generator.to_str().unwrap(),
        "--expr",
        "surprise",
        "--frames",
        "30",
        "--onset",
        "5",
        "--apex",
        "10:20",
        "--offset",
        "25",
        "--fps",
        "24",
        "--preview",
        sheet.to_str().unwrap(),
        "--json",
    ]));
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["frames"], 30);
    let animation = read_morph_animation(&glb).unwrap();
    assert_eq!(animation.frames.len(), 30);
    assert!((animation.fps - 24.0).abs() < 1e-6);
    let rest = read_mesh(&neutral).unwrap();
    assert_eq!(animation.mesh.triangles(), rest.triangles());
    assert!(std::fs::metadata(&sheet).unwrap().len() > 1000);
    // A curve mixing two expressions, written as frames.
    let curve = dir.path().join("curve.csv");
    std::fs::write(
        &curve,
        "frame,expression,amplitude\n0,happy,0\n6,happy,1\n3,fear,0.5\n",
    )
    .unwrap();
    let frames = dir.path().join("frames");
    ok(&express(&[
        "generate",
        "-o",
        frames.to_str().unwrap(),
        "--weights",
        f.generator.to_str().unwrap(),
        "--curve",
        curve.to_str().unwrap(),
    ]));
    assert_eq!(std::fs::read_dir(&frames).unwrap().count(), 7);
    assert!(read_mesh(frames.join("frame_0006.ply")).is_ok());
}

#[test]
fn bad_requests_get_one_line_errors() {
    let f = fixture();
    let dir = tempfile::tempdir().unwrap();
    let weights = f.generator.to_str().unwrap();
    let out = dir.path().join("a.glb");
    let other = dir.path().join("sphere.ply");
    write_mesh(&other, &icosphere(1)).unwrap();
    let err = fails(&express(&[
        "generate",
        other.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--weights",
        weights,
    ]));
    assert!(
        err.contains("sphere.ply") && err.contains("42 vertices") && err.contains("2800"),
        "{err}"
    );
    let curve = dir.path().join("bad.csv");
    for (text, needle) in [
        ("0,grin,1", "unknown expression `grin`"),
        ("-1,happy,0.5", "frame `-1`"),
        ("0,happy,2", "outside [0, 1]"),
    ] {
        std::fs::write(&curve, text).unwrap();
        let err = fails(&express(&[
            "generate",
            "-o",
            out.to_str().unwrap(),
            "--weights",
            weights,
            "--curve",
            curve.to_str().unwrap(),
        ]));
        assert!(err.contains("bad.csv:1") && err.contains(needle), "{err}");
    }
    let err = fails(&express(&[
        "generate",
        "-o",
        out.to_str().unwrap(),
        "--weights",
        weights,
        "--apex",
        "40:20",
    ]));
    assert!(err.contains("must increase"), "{err}");
    let err = fails(&express(&[
        "generate",
        "-o",
        dir.path().join("one.ply").to_str().unwrap(),
        "--weights",
        weights,
    ]));
    assert!(
        err.contains("one.ply") && err.contains("write a .glb"),
        "{err}"
    );
    assert!(!out.exists());
    // Never overwrite the input.
    let err = fails(&express(&[
        "generate",
        other.to_str().unwrap(),
        "-o",
        other.to_str().unwrap(),
        "--weights",
        weights,
    ]));
    assert!(err.contains("sphere.ply"), "{err}");
}
