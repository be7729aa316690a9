//! `handy` refuses nonsense arguments with one line naming the flag and the fix, before
//! reading a model or allocating anything.
#![allow(clippy::expect_used, clippy::unwrap_used, clippy::panic)]

use std::process::{Command, Output};
use std::time::{Duration, Instant};

use meshgnn_geometry::{icosphere, write_mesh};

fn handy(args: &[&str]) -> (Output, Duration) {
    let start = Instant::now();
    let out = Command::new(env!("CARGO_BIN_EXE_handy"))
        .args(args)
        .output()
        .expect("the binary runs");
    (out, start.elapsed())
}

/// Non-zero exit and one error line containing every one of `needles` (argument-parsing
/// errors may add clap's "For more information, try '--help'." hint below it).
fn assert_refused(out: &Output, needles: &[&str]) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    let lines: Vec<&str> = stderr
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with("For more information"))
        .collect();
    assert_eq!(lines.len(), 1, "{stderr}");
    for needle in needles {
        assert!(lines[0].contains(needle), "missing {needle:?} in {stderr}");
    }
}

#[test]
fn a_camera_at_the_origin_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let scan = dir.path().join("scan.obj");
    write_mesh(&scan, &icosphere(2)).unwrap();
    let fit = dir.path().join("fit.obj");
    let (out, _) = handy(&[
        "fit",
        scan.to_str().unwrap(),
        "-o",
        fit.to_str().unwrap(),
        "--camera",
        "0,0,0",
    ]);
    assert_refused(&out, &["--camera", "non-zero length"]);
    assert!(!fit.exists());
}

#[test]
fn interpolation_steps_are_bounded_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.obj");
    write_mesh(&a, &icosphere(1)).unwrap();
    let output = dir.path().join("frames");
    let (out, took) = handy(&[
        "interpolate",
        a.to_str().unwrap(),
        a.to_str().unwrap(),
        "--steps",
        "100000",
        "-o",
        output.to_str().unwrap(),
    ]);
    assert_refused(&out, &["--steps", "100000"]);
    assert!(!output.exists(), "nothing written");
    assert!(took < Duration::from_secs(20), "refused in {took:?}");
}

#[test]
fn sample_count_is_bounded() {
    let dir = tempfile::tempdir().unwrap();
    let output = dir.path().join("samples");
    let (out, _) = handy(&["sample", "-n", "100000000", "-o", output.to_str().unwrap()]);
    assert_refused(&out, &["100000000"]);
    assert!(!output.exists(), "nothing written");
}
