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

#[test]
fn a_folder_is_simplified_file_by_file_and_a_bad_file_never_stops_the_batch() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in");
    std::fs::create_dir(&input).unwrap();
    write_mesh(input.join("a_sphere.ply"), &icosphere(3)).unwrap();
    write_mesh(
        input.join("b_cube.obj"),
        &meshgnn_geometry::subdivided_cube(4),
    )
    .unwrap();
    std::fs::write(input.join("c_broken.obj"), "f 1 2 3\n").unwrap();
    std::fs::write(input.join("notes.txt"), "not a mesh").unwrap();
    let output = dir.path().join("out");
    let (i, o) = (input.to_str().unwrap(), output.to_str().unwrap());
    let out = meshsimplify(&["simplify", i, "-o", o, "--ratio", "0.25", "--json"]);
    assert!(!out.status.success(), "a failed file must fail the run");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("1 of 3 mesh files"), "{stderr}");
    let lines: Vec<Value> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 3);
    assert_eq!(lines[0]["input_faces"], 1280);
    assert_eq!(lines[0]["output_faces"], 320);
    assert!(lines[1]["output_faces"].as_u64().unwrap() > 0);
    assert!(
        lines[2]["failure"]
            .as_str()
            .unwrap()
            .contains("c_broken.obj")
    );
    for (name, line) in [("a_sphere.ply", &lines[0]), ("b_cube.obj", &lines[1])] {
        let written = read_mesh(output.join(name)).unwrap();
        assert_eq!(
            written.face_count() as u64,
            line["output_faces"].as_u64().unwrap()
        );
        assert!(line["output"].as_str().unwrap().ends_with(name));
    }
    assert!(!output.join("c_broken.obj").exists());
    assert!(!output.join("notes.txt").exists());

    // Without the broken file the run succeeds, byte-identical to the first.
    let first = std::fs::read(output.join("a_sphere.ply")).unwrap();
    std::fs::remove_file(input.join("c_broken.obj")).unwrap();
    let again = dir.path().join("again");
    let a = again.to_str().unwrap();
    let out = meshsimplify(&["simplify", i, "-o", a, "--ratio", "0.25"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(std::fs::read(again.join("a_sphere.ply")).unwrap(), first);

    // The output folder may not be the input folder: refused before anything is written.
    let before = std::fs::read(input.join("b_cube.obj")).unwrap();
    let out = meshsimplify(&["simplify", i, "-o", i, "--faces", "10"]);
    assert!(!out.status.success());
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("refusing to write"),
        "{:?}",
        out
    );
    assert_eq!(std::fs::read(input.join("b_cube.obj")).unwrap(), before);
}
