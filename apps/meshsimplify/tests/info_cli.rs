//! End-to-end tests of `meshsimplify info`: the binary run as a user runs it.
#![allow(clippy::expect_used)]

use std::path::Path;
use std::process::Command;

use serde_json::Value;

fn meshsimplify(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_meshsimplify"))
        .args(args)
        .output()
        .expect("the binary runs")
}

/// A closed octahedron: 6 vertices, 12 edges, 8 faces, one component.
const OCTAHEDRON_OFF: &str = "OFF\n6 8 0\n1 0 0\n-1 0 0\n0 1 0\n0 -1 0\n0 0 1\n0 0 -1\n\
3 0 2 4\n3 2 1 4\n3 1 3 4\n3 3 0 4\n3 2 0 5\n3 1 2 5\n3 3 1 5\n3 0 3 5\n";

#[test]
fn json_report_has_the_documented_keys_and_values() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("octahedron.off");
    std::fs::write(&file, OCTAHEDRON_OFF).unwrap();
    let out = meshsimplify(&["info", file.to_str().unwrap(), "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(report["vertices"], 6);
    assert_eq!(report["faces"], 8);
    assert_eq!(report["edges"], 12);
    assert_eq!(report["edge_manifold"], true);
    assert_eq!(report["vertex_manifold"], true);
    assert_eq!(report["watertight"], true);
    assert_eq!(report["boundary_loops"], 0);
    assert_eq!(report["components"], 1);
    assert_eq!(report["degenerate_faces"], 0);
    assert_eq!(report["misoriented_edges"], 0);
    assert_eq!(report["bbox_min"], serde_json::json!([-1.0, -1.0, -1.0]));
    assert_eq!(report["bbox_max"], serde_json::json!([1.0, 1.0, 1.0]));
    assert!(report["load_seconds"].as_f64().unwrap() >= 0.0);
}

#[test]
fn a_folder_is_reported_file_by_file() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["a.off", "b.off"] {
        std::fs::write(dir.path().join(name), OCTAHEDRON_OFF).unwrap();
    }
    std::fs::write(dir.path().join("notes.txt"), "not a mesh").unwrap();
    let out = meshsimplify(&["info", dir.path().to_str().unwrap(), "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let reports: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(reports.as_array().unwrap().len(), 2);
}

#[test]
fn a_missing_file_fails_with_one_line_naming_it() {
    let out = meshsimplify(&["info", "no/such/mesh.ply"]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(stderr.contains("no/such/mesh.ply"), "{stderr}");
}

#[test]
fn a_malformed_file_fails_naming_file_and_problem() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("broken.off");
    std::fs::write(&file, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n").unwrap();
    let out = meshsimplify(&["info", file.to_str().unwrap()]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(stderr.contains("broken.off"), "{stderr}");
    assert!(Path::new(&file).exists(), "the input is untouched");
}

#[test]
fn a_reader_that_has_gone_ends_the_run_quietly() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("octahedron.off");
    std::fs::write(&file, OCTAHEDRON_OFF).unwrap();
    // the read end closed before the run starts: its first line on stdout meets a broken pipe,
    // as under `meshsimplify info F | head -0`
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    let out = Command::new(env!("CARGO_BIN_EXE_meshsimplify"))
        .args(["info", file.to_str().unwrap()])
        .stdout(writer)
        .output()
        .expect("the binary runs");
    assert_eq!(
        out.status.code(),
        Some(meshgnn_geometry::BROKEN_PIPE_STATUS),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn a_full_disk_behind_stdout_is_one_line_on_stderr() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("octahedron.off");
    std::fs::write(&file, OCTAHEDRON_OFF).unwrap();
    let Ok(full) = std::fs::OpenOptions::new().write(true).open("/dev/full") else {
        return; // no /dev/full on this system
    };
    let out = Command::new(env!("CARGO_BIN_EXE_meshsimplify"))
        .args(["info", file.to_str().unwrap()])
        .stdout(full)
        .output()
        .expect("the binary runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("writing to standard output"), "{stderr}");
}

#[test]
fn an_error_whose_stderr_reader_has_gone_still_exits_with_status_1() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.off");
    // `eprintln!` would panic here (status 101) on the error line it cannot write.
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    let out = Command::new(env!("CARGO_BIN_EXE_meshsimplify"))
        .args(["info", missing.to_str().unwrap()])
        .stderr(writer)
        .output()
        .expect("the binary runs");
    assert_eq!(out.status.code(), Some(1));
}
