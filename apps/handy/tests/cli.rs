//! End-to-end tests of `handy`: the binary run as a user runs it, on a tiny hand dataset
//! (717-vertex template, 40 subjects) written to a temporary folder.
#![allow(clippy::expect_used, clippy::unwrap_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

use meshgnn_data::{
    HandPose, HandSetConfig, HandShape, HandTemplate, Manifest, hand_splits, write_dataset,
};
use meshgnn_geometry::{PointCloud, TriMesh, icosphere, read_mesh, write_mesh, write_point_cloud};
use serde_json::Value;

fn handy(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_handy"))
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

/// Tiny dataset + a model trained on it for one epoch, shared by the tests.
struct Fixture {
    _dir: tempfile::TempDir,
    data: PathBuf,
    model: PathBuf,
}

fn write_hands(root: &Path, count: usize) {
    let cfg = HandSetConfig {
        count,
        seed: 3,
        subdivisions: 1,
        children_fraction: 0.3,
        test_fraction: 0.4,
        ..Default::default()
    };
    let template = HandTemplate::new(1).unwrap();
    let samples: Vec<_> = (0..count)
        .map(|i| cfg.sample(&template, i).unwrap())
        .collect();
    let meshes: Vec<(String, TriMesh)> = samples
        .iter()
        .map(|s| {
            let m = TriMesh::new(s.vertices.clone(), template.triangles().to_vec()).unwrap();
            (format!("{}.ply", s.name), m)
        })
        .collect();
    let rest = template
        .generate(&HandShape::adult(), &HandPose::rest())
        .unwrap();
    let manifest = Manifest {
        format_version: 1,
        description: "tiny test hands".into(),
        template: Some("template.ply".into()),
        splits: hand_splits(&samples, "ply"),
        labels: Default::default(),
    };
    write_dataset(root, &manifest, Some(&rest), &meshes).unwrap();
}

fn fixture() -> &'static Fixture {
    static FIXTURE: OnceLock<Fixture> = OnceLock::new();
    FIXTURE.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let data = dir.path().join("hands");
        write_hands(&data, 40);
        let model = dir.path().join("model.safetensors");
        let out = handy(&[
            "train",
            data.to_str().unwrap(),
            "--latent",
            "4",
            "--levels",
            "3",
            "-o",
            model.to_str().unwrap(),
            "--epochs",
            "2",
            "--batch-size",
            "8",
            "--json",
        ]);
        let summary: Value = serde_json::from_str(&ok(&out)).unwrap();
        assert_eq!(summary["latent"], 4);
        assert!(summary["train_mm"].as_f64().unwrap() > 0.0);
        assert!(summary["val_mm"].as_f64().is_some());
        Fixture {
            _dir: dir,
            data,
            model,
        }
    })
}

fn test_files(f: &Fixture) -> Vec<PathBuf> {
    let manifest: Value =
        serde_json::from_slice(&std::fs::read(f.data.join("dataset.json")).unwrap()).unwrap();
    manifest["splits"]["test"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| f.data.join(n.as_str().unwrap()))
        .collect()
}

#[test]
fn eval_reports_table_3_2_and_3_5_as_json() {
    let f = fixture();
    let out = handy(&[
        "eval",
        f.data.to_str().unwrap(),
        "--model",
        f.model.to_str().unwrap(),
        "--samples",
        "20",
        "--fit-scans",
        "1",
        "--fit-steps",
        "5",
        "--scan-points",
        "2000",
        "--json",
    ]);
    let r: Value = serde_json::from_str(&ok(&out)).unwrap();
    assert_eq!(r["latent"], 4);
    for key in ["ae_mm", "pca_mm"] {
        let v = r[key].as_f64().unwrap();
        assert!(v > 0.0 && v < 100.0, "{key} = {v}");
    }
    assert_eq!(
        r["test_meshes"].as_u64().unwrap() as usize,
        test_files(f).len()
    );
    assert!(r["splits"]["children"]["pca"]["mean"].as_f64().is_some());
    assert!(r["specificity"]["ae"]["mean"].as_f64().unwrap() > 0.0);
    let c = r["compactness"]["pca_explained_at_latent"]
        .as_f64()
        .unwrap();
    assert!(c > 0.0 && c <= 1.0);
    assert!(r["fitting"]["ae"]["r2s_mm"].as_f64().unwrap() > 0.0);
    assert!(r["fitting"]["pca"]["s2r_mm"].as_f64().unwrap() > 0.0);
    // the text table names both models
    let text = ok(&handy(&[
        "eval",
        f.data.to_str().unwrap(),
        "--model",
        f.model.to_str().unwrap(),
        "--samples",
        "5",
        "--fit-scans",
        "0",
    ]));
    assert!(text.contains("Handy++ (n_z = 4)") && text.contains("Handy (PCA, n_c = 4)"));
}

#[test]
fn sample_writes_meshes_on_the_template_and_a_contact_sheet() {
    let f = fixture();
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("s");
    let model = f.model.to_str().unwrap();
    ok(&handy(&[
        "sample",
        "-n",
        "3",
        "-o",
        out_dir.to_str().unwrap(),
        "--model",
        model,
        "--seed",
        "5",
    ]));
    let template = read_mesh(f.data.join("template.ply")).unwrap();
    for i in 0..3 {
        let m = read_mesh(out_dir.join(format!("sample_{i:03}.obj"))).unwrap();
        assert_eq!(m.triangles(), template.triangles());
    }
    assert!(!out_dir.join("sample_003.obj").exists());
    assert!(
        std::fs::metadata(out_dir.join("samples.png"))
            .unwrap()
            .len()
            > 100
    );
    // same seed, same hands; --preview puts the same sheet where it is asked for
    let again = dir.path().join("t");
    let sheet = dir.path().join("sheet.png");
    ok(&handy(&[
        "sample",
        "-n",
        "3",
        "-o",
        again.to_str().unwrap(),
        "--model",
        model,
        "--seed",
        "5",
        "--preview",
        sheet.to_str().unwrap(),
    ]));
    assert_eq!(
        std::fs::read(out_dir.join("sample_001.obj")).unwrap(),
        std::fs::read(again.join("sample_001.obj")).unwrap()
    );
    assert_eq!(
        std::fs::read(out_dir.join("samples.png")).unwrap(),
        std::fs::read(&sheet).unwrap()
    );
    assert!(!again.join("samples.png").exists());
}

/// Width and height of a PNG file (its IHDR chunk).
fn png_size(path: &Path) -> (u32, u32) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    let word =
        |at: usize| u32::from_be_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    (word(16), word(20))
}

#[test]
fn fit_recovers_a_scan_of_a_test_hand() {
    let f = fixture();
    let dir = tempfile::tempdir().unwrap();
    let hand = read_mesh(&test_files(f)[0]).unwrap();
    let scan = dir.path().join("scan.ply");
    write_point_cloud(&scan, &PointCloud::new(hand.vertices().to_vec()).unwrap()).unwrap();
    let fitted = dir.path().join("fitted.obj");
    let out = handy(&[
        "fit",
        scan.to_str().unwrap(),
        "-o",
        fitted.to_str().unwrap(),
        "--model",
        f.model.to_str().unwrap(),
        "--steps",
        "30",
        "--preview",
        dir.path().join("fit.png").to_str().unwrap(),
        "--json",
    ]);
    let r: Value = serde_json::from_str(&ok(&out)).unwrap();
    // front, side and top views of the scan over the fit
    assert_eq!(png_size(&dir.path().join("fit.png")), (1200, 400));
    assert!(r["preview"].as_str().unwrap().ends_with("fit.png"), "{r}");
    let (r2s, s2r) = (r["r2s_mm"].as_f64().unwrap(), r["s2r_mm"].as_f64().unwrap());
    assert!(r2s > 0.0 && r2s < 30.0 && s2r > 0.0 && s2r < 30.0, "{r}");
    let diagonal = meshgnn_geometry::bounding_box_diagonal(hand.vertices());
    let relative = r["r2s_relative"].as_f64().unwrap();
    assert!((relative - r2s / diagonal).abs() < 1e-9, "{r}");
    assert_eq!(r["mirrored"], Value::Bool(false), "{r}");
    assert_eq!(
        read_mesh(&fitted).unwrap().vertex_count(),
        hand.vertex_count()
    );
    let text = ok(&handy(&[
        "fit",
        scan.to_str().unwrap(),
        "-o",
        fitted.to_str().unwrap(),
        "--model",
        f.model.to_str().unwrap(),
        "--steps",
        "2",
    ]));
    assert!(text.contains("R2S") && text.contains("S2R"));
}

#[test]
fn interpolate_ends_at_the_reconstructions() {
    let f = fixture();
    let dir = tempfile::tempdir().unwrap();
    let files = test_files(f);
    let out_dir = dir.path().join("i");
    ok(&handy(&[
        "interpolate",
        files[0].to_str().unwrap(),
        files[1].to_str().unwrap(),
        "--steps",
        "3",
        "-o",
        out_dir.to_str().unwrap(),
        "--model",
        f.model.to_str().unwrap(),
    ]));
    let meshes: Vec<TriMesh> = (0..3)
        .map(|i| read_mesh(out_dir.join(format!("interp_{i:03}.obj"))).unwrap())
        .collect();
    // both ends are the model's reconstructions of the inputs
    let model =
        meshgnn_models::spiral::SpiralMorphableModel::load(&f.model, &candle_core::Device::Cpu)
            .unwrap();
    for (mesh, file) in [(&meshes[0], &files[0]), (&meshes[2], &files[1])] {
        let input = read_mesh(file).unwrap().vertices().to_vec();
        let rec = meshgnn_models::reconstruct_shapes(&model, &[input]).unwrap();
        let err = meshgnn_losses::metrics::per_vertex_error(mesh.vertices(), &rec[0]).unwrap();
        assert!(err < 1e-3, "{err}");
    }
    // the middle differs from both ends
    let d = meshgnn_losses::metrics::per_vertex_error(meshes[1].vertices(), meshes[0].vertices())
        .unwrap();
    assert!(d > 1e-3);
    assert!(out_dir.join("interpolation.png").exists());
}

#[test]
fn topology_mismatch_is_refused_naming_the_file() {
    let f = fixture();
    let dir = tempfile::tempdir().unwrap();
    // a hand mesh from another template resolution
    let other = dir.path().join("sphere.obj");
    write_mesh(&other, &icosphere(2)).unwrap();
    let files = test_files(f);
    let out = handy(&[
        "interpolate",
        files[0].to_str().unwrap(),
        other.to_str().unwrap(),
        "-o",
        dir.path().join("o").to_str().unwrap(),
        "--model",
        f.model.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("sphere.obj"), "{err}");
    // a dataset whose meshes differ from the model's template: the first file is named
    let coarse = dir.path().join("coarse");
    write_hands(&coarse, 6);
    let template = coarse.join("template.ply");
    let m = read_mesh(&template).unwrap();
    let moved = TriMesh::new(
        m.vertices().to_vec(),
        m.triangles().iter().map(|t| [t[1], t[2], t[0]]).collect(),
    )
    .unwrap();
    // rotate the index order of every face in every file: same shape, different triangles
    // than the model's template
    for entry in std::fs::read_dir(&coarse).unwrap() {
        let p = entry.unwrap().path();
        if p.extension().is_some_and(|e| e == "ply") && p != template {
            let mesh = read_mesh(&p).unwrap();
            let tri = moved.triangles().to_vec();
            write_mesh(&p, &TriMesh::new(mesh.vertices().to_vec(), tri).unwrap()).unwrap();
        }
    }
    let eval = || {
        handy(&[
            "eval",
            coarse.to_str().unwrap(),
            "--model",
            f.model.to_str().unwrap(),
            "--fit-scans",
            "0",
        ])
    };
    let out = eval();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    let manifest: Value =
        serde_json::from_slice(&std::fs::read(coarse.join("dataset.json")).unwrap()).unwrap();
    let first = manifest["splits"]["train"][0].as_str().unwrap();
    assert!(err.contains(first), "{err}");
    // a folder on another template: the folder is named with the template the model expects
    // and the command that writes hands on it
    write_mesh(&template, &moved).unwrap();
    let out = eval();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(
        err.contains(coarse.to_str().unwrap())
            && err.contains("template of 717 vertices")
            && err.contains("synth hands --subdivisions 1"),
        "{err}"
    );
}

#[test]
fn the_built_in_model_samples_hands() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s");
    ok(&handy(&["sample", "-n", "2", "-o", out.to_str().unwrap()]));
    let m = read_mesh(out.join("sample_000.obj")).unwrap();
    assert_eq!(m.vertex_count(), 2833);
    // a hand is 90-200 mm long
    let (lo, hi) = m
        .vertices()
        .iter()
        .fold((f32::MAX, f32::MIN), |(lo, hi), p| {
            (lo.min(p[1]), hi.max(p[1]))
        });
    assert!((80.0..260.0).contains(&(hi - lo)), "{}", hi - lo);
}

#[test]
fn bad_arguments_exit_non_zero() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("nothing");
    for args in [
        vec!["train"],
        vec!["train", missing.to_str().unwrap(), "-o", "x.safetensors"],
        vec!["sample", "-n", "abc", "-o", "x"],
        vec![
            "sample",
            "-n",
            "0",
            "-o",
            dir.path().join("z").to_str().unwrap(),
        ],
        vec!["fit", missing.to_str().unwrap(), "-o", "x.obj"],
        vec!["eval", missing.to_str().unwrap(), "--camera", "1,2"],
        vec!["frobnicate"],
    ] {
        let out = handy(&args);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(!out.stderr.is_empty(), "{args:?} printed no error");
    }
    let bad_model = dir.path().join("bad.safetensors");
    std::fs::write(&bad_model, b"not a model").unwrap();
    let out = handy(&[
        "sample",
        "-o",
        dir.path().join("y").to_str().unwrap(),
        "--model",
        bad_model.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("bad.safetensors"));
}
