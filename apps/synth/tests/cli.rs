//! End-to-end: each subcommand writes a folder dataset that `FolderDataset` reopens.

use std::process::Command;

use meshgnn_data::FolderDataset;

fn synth(args: &[&str]) {
    let ok = Command::new(env!("CARGO_BIN_EXE_synth"))
        .args(args)
        .status()
        .is_ok_and(|s| s.success());
    assert!(ok, "synth {args:?} failed");
}

#[test]
fn hands_faces_and_shapes_write_reloadable_datasets() {
    let dir = tempfile::tempdir().unwrap();
    let hands = dir.path().join("hands");
    let png = dir.path().join("hands.png");
    synth(&[
        "hands",
        "-n",
        "6",
        "--seed",
        "1",
        "--subdivisions",
        "1",
        "-o",
        hands.to_str().unwrap(),
        "--preview",
        png.to_str().unwrap(),
    ]);
    let ds = FolderDataset::open(&hands).unwrap();
    let total: usize = ds.manifest().splits.values().map(Vec::len).sum();
    assert_eq!(total, 6);
    assert_eq!(
        ds.load_split("train").unwrap().len(),
        ds.split("train").unwrap().len()
    );
    assert_eq!(&std::fs::read(&png).unwrap()[1..4], b"PNG");

    let faces = dir.path().join("faces");
    synth(&[
        "faces",
        "-n",
        "2",
        "--frame-step",
        "30",
        "-o",
        faces.to_str().unwrap(),
    ]);
    let ds = FolderDataset::open(&faces).unwrap();
    assert_eq!(
        ds.split("test").unwrap().len() + ds.split("train").unwrap().len(),
        ds.manifest().labels.len()
    );

    let shapes = dir.path().join("shapes");
    synth(&[
        "shapes",
        "--per-family",
        "1",
        "--resolution",
        "24",
        "--lidar",
        "0",
        "-o",
        shapes.to_str().unwrap(),
    ]);
    let ds = FolderDataset::open(&shapes).unwrap();
    assert!(ds.template().is_none());
    assert_eq!(ds.load_split("test").unwrap().len(), 2);
}

/// Every count is checked before anything is generated: one line naming the flag and its
/// range, a non-zero exit, and no output folder created.
#[test]
fn counts_out_of_range_are_refused_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    for (args, expected) in [
        (
            &["hands", "-n", "0"][..],
            "invalid -n: 0 is outside 1..=100000",
        ),
        (
            &["hands", "-n", "100001"][..],
            "invalid -n: 100001 is outside 1..=100000",
        ),
        (&["hands", "--subdivisions", "9"][..], "subdivisions"),
        (
            &["faces", "-n", "10001"][..],
            "invalid -n: 10001 is outside 1..=10000",
        ),
        (
            &["faces", "--frame-step", "0"][..],
            "invalid --frame-step: 0",
        ),
        (
            &["shapes", "--per-family", "1001"][..],
            "invalid --per-family: 1001",
        ),
        (
            &["shapes", "--resolution", "4"][..],
            "invalid --resolution: 4 is outside 8..=512",
        ),
        (
            &["shapes", "--resolution", "100000"][..],
            "invalid --resolution: 100000",
        ),
        (
            &["shapes", "--lidar", "101"][..],
            "invalid --lidar: 101 is outside 0..=100",
        ),
    ] {
        let output = dir.path().join("out");
        let out = Command::new(env!("CARGO_BIN_EXE_synth"))
            .args(args)
            .arg("-o")
            .arg(&output)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{args:?}: {stderr}");
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
        assert!(!output.exists(), "{args:?} wrote {}", output.display());
    }
}

/// `faces --full` is the thesis-size set; it cannot be combined with a subject count.
#[test]
fn faces_full_and_a_count_are_exclusive() {
    let dir = tempfile::tempdir().unwrap();
    let output = dir.path().join("out");
    let out = Command::new(env!("CARGO_BIN_EXE_synth"))
        .args(["faces", "--full", "-n", "3", "-o"])
        .arg(&output)
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--full"));
    assert!(!output.exists());
}
