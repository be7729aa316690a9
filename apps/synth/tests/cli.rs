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
