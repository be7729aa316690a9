//! Bad files and odd arguments: every subcommand refuses them with one line that names the
//! right file (or flag) and the problem, and exits non-zero.
#![allow(clippy::expect_used, clippy::unwrap_used)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// Runs the binary; returns (success, stdout, stderr).
fn meshsimplify(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_meshsimplify"))
        .args(args)
        .output()
        .expect("the binary runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Runs a command that must fail; returns its stderr, which must be one line.
fn refused(args: &[&str]) -> String {
    let (ok, _, stderr) = meshsimplify(args);
    assert!(!ok, "{args:?} succeeded");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    stderr
}

/// A closed tetrahedron.
const TETRAHEDRON: &str =
    "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

/// Writes the test files into `dir` and returns the path of `name`.
fn file(dir: &Path, name: &str, content: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, content).unwrap();
    path
}

struct Files {
    _dir: tempfile::TempDir,
    good: String,
    empty: String,
    random: String,
    faceless: String,
    huge: String,
}

fn files() -> Files {
    let dir = tempfile::tempdir().unwrap();
    let s = |p: PathBuf| p.to_str().unwrap().to_string();
    Files {
        good: s(file(dir.path(), "good.obj", TETRAHEDRON)),
        empty: s(file(dir.path(), "empty.obj", "")),
        random: s(file(dir.path(), "random.obj", "qL0x9 Zr/+ aa\n%%%\n7fj\n")),
        faceless: s(file(
            dir.path(),
            "faceless.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\n",
        )),
        huge: s(file(
            dir.path(),
            "huge.obj",
            &TETRAHEDRON.replace("v 0 0 1\n", "v 0 0 1e38\n"),
        )),
        _dir: dir,
    }
}

#[test]
fn info_refuses_an_empty_or_random_text_file() {
    let f = files();
    for bad in [&f.empty, &f.random] {
        let message = refused(&["info", bad]);
        assert!(
            message.contains(&format!("{bad}: content: no vertices")),
            "{message}"
        );
    }
}

#[test]
fn info_on_a_folder_reports_the_good_files_lists_the_bad_and_fails() {
    let f = files();
    let dir = Path::new(&f.good).parent().unwrap().to_str().unwrap();
    let (ok, stdout, stderr) = meshsimplify(&["info", dir, "--json"]);
    assert!(!ok);
    let reports: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    let names: Vec<&str> = reports
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["file"].as_str().unwrap())
        .collect();
    // the faceless and the good mesh are reported; the huge one is refused
    assert_eq!(names, [f.faceless.as_str(), f.good.as_str()]);
    for bad in [&f.empty, &f.huge, &f.random] {
        assert!(stderr.contains(&format!("{bad}: ")), "{stderr}");
    }
    assert!(
        stderr.contains("3 of 5 mesh files in") && stderr.contains("could not be reported"),
        "{stderr}"
    );
}

#[test]
fn info_on_an_empty_folder_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let message = refused(&["info", dir.path().to_str().unwrap()]);
    assert!(message.contains("holds no mesh file"), "{message}");
}

#[test]
fn eval_names_the_bad_original() {
    let f = files();
    let message = refused(&["eval", &f.empty, &f.good]);
    assert!(
        message.contains(&format!(
            "reading the original mesh: {}: content: no vertices",
            f.empty
        )),
        "{message}"
    );
    let message = refused(&["eval", &f.faceless, &f.good]);
    assert!(
        message.contains(&format!(
            "reading the original mesh: {}: mesh: 3 vertices but no faces",
            f.faceless
        )),
        "{message}"
    );
}

#[test]
fn eval_names_the_bad_simplified_mesh() {
    let f = files();
    let message = refused(&["eval", &f.good, &f.random]);
    assert!(
        message.contains(&format!("reading the simplified mesh: {}: ", f.random)),
        "{message}"
    );
}

#[test]
fn eval_refuses_coordinates_too_large_to_square() {
    let f = files();
    let message = refused(&["eval", &f.huge, &f.good]);
    assert!(
        message.contains(&format!(
            "reading the original mesh: {}: vertex 3: coordinate 1e38 is beyond ±1e18",
            f.huge
        )) && message.contains("rescale the model"),
        "{message}"
    );
}

#[test]
fn eval_bounds_the_sample_count() {
    let f = files();
    for (samples, value) in [("0", "0"), ("10000001", "10000001")] {
        let message = refused(&["eval", &f.good, &f.good, "--samples", samples]);
        assert!(
            message.contains(&format!(
                "invalid --samples: {value} is outside 1..=10000000"
            )),
            "{message}"
        );
    }
}

#[test]
fn simplify_names_a_file_without_faces() {
    let f = files();
    let out = Path::new(&f.good).with_file_name("out.obj");
    let message = refused(&[
        "simplify",
        &f.faceless,
        "-o",
        out.to_str().unwrap(),
        "--ratio",
        "0.5",
    ]);
    assert!(
        message.contains(&format!("{}: mesh: 3 vertices but no faces", f.faceless)),
        "{message}"
    );
    assert!(!out.exists());
}

#[test]
fn the_selecting_methods_give_a_result_or_one_line_naming_the_file() {
    let f = files();
    let out = Path::new(&f.good).with_file_name("out.ply");
    let out = out.to_str().unwrap();
    let run = |input: &str, method: &str| {
        meshsimplify(&[
            "simplify", input, "-o", out, "--ratio", "0.5", "--method", method,
        ])
    };
    // Too small for the neural method: refused, naming the file and the limit.
    let message = refused(&[
        "simplify", &f.good, "-o", out, "--ratio", "0.5", "--method", "neural",
    ]);
    assert!(
        message.contains(&f.good) && message.contains("at least 100"),
        "{message}"
    );
    // pc+remesh re-meshes what it keeps; the faceless file is named as for qem.
    let (ok, _, stderr) = run(&f.good, "pc+remesh");
    assert!(ok, "{stderr}");
    for method in ["neural", "pc+remesh"] {
        let message = refused(&[
            "simplify",
            &f.faceless,
            "-o",
            out,
            "--ratio",
            "0.5",
            "--method",
            method,
        ]);
        assert!(message.contains("no faces"), "{message}");
    }
}

#[test]
fn simplify_refuses_face_targets_it_cannot_reach() {
    let f = files();
    let out = Path::new(&f.good).with_file_name("out.obj");
    let out = out.to_str().unwrap();
    for (flag, value, expected) in [
        (
            "--faces",
            "10",
            "--faces 10 is more than the input's 4 faces",
        ),
        ("--faces", "0", "--faces 0: keep at least 1 face"),
        (
            "--ratio",
            "0.01",
            "--ratio 0.01 keeps 0 of the input's 4 faces",
        ),
        ("--ratio", "NaN", "--ratio NaN is outside (0, 1]"),
        ("--ratio", "1.5", "--ratio 1.5 is outside (0, 1]"),
    ] {
        let message = refused(&["simplify", &f.good, "-o", out, flag, value]);
        assert!(message.contains(expected), "{flag} {value}: {message}");
    }
}
