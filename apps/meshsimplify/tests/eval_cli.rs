//! End-to-end tests of `meshsimplify eval`: the binary run as a user runs it.
#![allow(clippy::expect_used, clippy::unwrap_used)]

use std::process::{Command, Output};

use meshgnn_geometry::{icosphere, write_mesh};
use serde_json::Value;

fn meshsimplify(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_meshsimplify"))
        .args(args)
        .output()
        .expect("the binary runs")
}

fn eval_json(original: &str, simplified: &str) -> Value {
    let out = meshsimplify(&["eval", original, simplified, "--json", "--samples", "5000"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn a_mesh_against_itself_scores_zero_and_a_simplification_does_not() {
    let dir = tempfile::tempdir().unwrap();
    let original = dir.path().join("sphere.ply");
    write_mesh(&original, &icosphere(4)).unwrap();
    let original = original.to_str().unwrap();
    let simplified = dir.path().join("small.ply");
    let simplified = simplified.to_str().unwrap();
    let out = meshsimplify(&["simplify", original, "-o", simplified, "--ratio", "0.05"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );

    let same = eval_json(original, original);
    for key in [
        "cd",
        "hausdorff",
        "ne",
        "wa",
        "le",
        "holes",
        "edge_manifold",
    ] {
        assert!(same.get(key).is_some(), "missing key {key}: {same}");
    }
    assert!(same["cd"].as_f64().unwrap() < 1e-9, "{same}");
    assert_eq!(same["wa"].as_f64().unwrap(), 0.0);
    assert_eq!(same["holes"], 0);
    assert_eq!(same["edge_manifold"], true);

    let coarse = eval_json(original, simplified);
    assert!(coarse["cd"].as_f64().unwrap() > 0.0, "{coarse}");
    assert!(coarse["hausdorff"].as_f64().unwrap() > 0.0, "{coarse}");
    assert_eq!(coarse["holes"], 0, "QEM keeps a closed mesh closed");
}

#[test]
fn a_missing_simplified_file_fails_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let original = dir.path().join("sphere.ply");
    write_mesh(&original, &icosphere(2)).unwrap();
    let out = meshsimplify(&["eval", original.to_str().unwrap(), "gone.ply"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("gone.ply"));
}
