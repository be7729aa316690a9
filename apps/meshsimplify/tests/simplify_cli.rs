//! End-to-end tests of `meshsimplify simplify`: the binary run as a user runs it.
#![allow(clippy::expect_used, clippy::unwrap_used)]

use std::path::Path;
use std::process::{Command, Output};

use meshgnn_geometry::{icosphere, mesh_report, read_mesh, write_mesh};
use serde_json::Value;

fn meshsimplify(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_meshsimplify"))
        .args(args)
        .output()
        .expect("the binary runs")
}

fn sphere_file(dir: &Path) -> String {
    let path = dir.join("sphere.ply");
    write_mesh(&path, &icosphere(4)).unwrap();
    path.to_str().unwrap().to_owned()
}

#[test]
fn ratio_reaches_the_target_and_keeps_the_mesh_closed() {
    let dir = tempfile::tempdir().unwrap();
    let input = sphere_file(dir.path());
    let output = dir.path().join("small.obj");
    let out = meshsimplify(&[
        "simplify",
        &input,
        "-o",
        output.to_str().unwrap(),
        "--ratio",
        "0.1",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let summary: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(summary["input_faces"], 5120);
    let faces = summary["output_faces"].as_u64().unwrap();
    assert!(faces.abs_diff(512) <= 6, "{faces} faces");
    assert!(summary["error"].as_f64().unwrap() >= 0.0);
    assert!(summary["seconds"].as_f64().unwrap() >= 0.0);
    let simplified = read_mesh(&output).unwrap();
    assert_eq!(simplified.face_count() as u64, faces);
    let report = mesh_report(&simplified);
    assert!(report.watertight && report.edge_manifold && report.vertex_manifold);
}

#[test]
fn refuses_to_overwrite_the_input_without_force() {
    let dir = tempfile::tempdir().unwrap();
    let input = sphere_file(dir.path());
    let before = std::fs::read(&input).unwrap();
    let out = meshsimplify(&["simplify", &input, "-o", &input, "--faces", "100"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--force"));
    assert_eq!(std::fs::read(&input).unwrap(), before, "input untouched");
}

#[test]
fn bad_arguments_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let input = sphere_file(dir.path());
    let output = dir.path().join("out.ply");
    let out_path = output.to_str().unwrap();
    for args in [
        vec!["simplify", &input, "-o", out_path, "--ratio", "1.5"],
        vec!["simplify", &input, "-o", out_path, "--ratio", "0"],
        vec![
            "simplify", &input, "-o", out_path, "--ratio", "0.5", "--method", "magic",
        ],
        vec!["simplify", "missing.ply", "-o", out_path, "--ratio", "0.5"],
        vec!["simplify", &input, "-o", out_path],
    ] {
        let out = meshsimplify(&args);
        assert!(!out.status.success(), "{args:?} should fail");
        assert!(!String::from_utf8_lossy(&out.stderr).trim().is_empty());
        assert!(!output.exists(), "{args:?} wrote a file");
    }
}
