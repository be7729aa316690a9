//! End-to-end tests of the output guard in `handy`: no output file, output folder, file
//! written into a folder or contact sheet may replace one of the command's inputs.
#![allow(clippy::expect_used, clippy::unwrap_used, clippy::panic)]

use std::path::Path;
use std::process::{Command, Output};

use meshgnn_geometry::{icosphere, write_mesh};

fn handy(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_handy"))
        .args(args)
        .output()
        .expect("the binary runs")
}

fn text(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// Asserts a refusal: non-zero exit, one line naming the output, the input and the fix.
fn assert_refused(out: &Output, output: &Path, input: &Path) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains(&format!("refusing to write {}", output.display())),
        "{stderr}"
    );
    assert!(
        stderr.contains(&format!("the input {}", input.display())),
        "{stderr}"
    );
    assert!(stderr.contains("write to another path"), "{stderr}");
}

#[test]
fn fit_onto_its_own_scan_is_refused_and_the_scan_kept() {
    let dir = tempfile::tempdir().unwrap();
    let scan = dir.path().join("scan.obj");
    write_mesh(&scan, &icosphere(2)).unwrap();
    let before = std::fs::read(&scan).unwrap();
    let out = handy(&["fit", text(&scan), "-o", text(&scan)]);
    assert_refused(&out, &scan, &scan);
    let dotted = dir.path().join(".").join("scan.obj");
    let out = handy(&["fit", text(&scan), "-o", text(&dotted)]);
    assert_refused(&out, &dotted, &scan);
    assert_eq!(std::fs::read(&scan).unwrap(), before, "scan untouched");
}

#[test]
fn train_onto_a_file_of_its_dataset_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let template = dir.path().join("template.ply");
    write_mesh(&template, &icosphere(1)).unwrap();
    let before = std::fs::read(&template).unwrap();
    let out = handy(&["train", text(dir.path()), "-o", text(&template)]);
    assert_refused(&out, &template, &template);
    assert_eq!(
        std::fs::read(&template).unwrap(),
        before,
        "dataset untouched"
    );
}

/// The contact sheet (the preview image of `interpolate`) and the meshes written into the
/// output folder are checked too: a sheet linked to an input hand, or an input hand named like
/// an output mesh, refuses the whole command before the folder is written.
#[cfg(unix)]
#[test]
fn interpolate_refuses_a_folder_whose_sheet_or_mesh_is_an_input() {
    let dir = tempfile::tempdir().unwrap();
    let hands = dir.path().join("hands");
    let out = handy(&["sample", "-n", "2", "-o", text(&hands)]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (a, b) = (hands.join("sample_000.obj"), hands.join("sample_001.obj"));

    let folder = dir.path().join("linked");
    std::fs::create_dir(&folder).unwrap();
    let sheet = folder.join("interpolation.png");
    std::os::unix::fs::symlink(&a, &sheet).unwrap();
    let before = std::fs::read(&a).unwrap();
    let out = handy(&["interpolate", text(&a), text(&b), "-o", text(&folder)]);
    assert_refused(&out, &sheet, &a);
    assert_eq!(std::fs::read(&a).unwrap(), before, "input hand untouched");
    assert_eq!(
        std::fs::read_dir(&folder).unwrap().count(),
        1,
        "nothing written"
    );

    let named = dir.path().join("named");
    std::fs::create_dir(&named).unwrap();
    let first = named.join("interp_000.obj");
    std::fs::copy(&b, &first).unwrap();
    let out = handy(&["interpolate", text(&a), text(&first), "-o", text(&named)]);
    assert_refused(&out, &first, &first);
    assert_eq!(std::fs::read(&first).unwrap(), std::fs::read(&b).unwrap());
}
