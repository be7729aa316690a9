//! Bad files and odd arguments: every subcommand refuses them with one line that names the
//! right file (or flag) and the problem, and exits non-zero.
#![allow(clippy::expect_used, clippy::unwrap_used)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// Runs a command that must fail; returns its stderr, which must be one line.
fn refused(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_pcsimplify"))
        .args(args)
        .output()
        .expect("the binary runs");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success(), "{args:?} succeeded");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    stderr
}

fn write(dir: &Path, name: &str, content: &str) -> String {
    let path: PathBuf = dir.join(name);
    std::fs::write(&path, content).unwrap();
    path.to_str().unwrap().to_string()
}

/// 64 points on a 4×4×4 grid.
fn grid() -> String {
    (0..64)
        .map(|i| format!("{} {} {}\n", i % 4, (i / 4) % 4, i / 16))
        .collect()
}

#[test]
fn an_empty_or_random_text_cloud_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.xyz");
    for (name, content) in [("empty.obj", ""), ("random.obj", "zz9 qq !!\n#x\n")] {
        let input = write(dir.path(), name, content);
        let message = refused(&[
            "simplify",
            &input,
            "-o",
            out.to_str().unwrap(),
            "--ratio",
            "0.5",
            "--method",
            "fps",
        ]);
        assert!(
            message.contains(&format!("{input}: content: no vertices")),
            "{message}"
        );
    }
    assert!(!out.exists());
}

#[test]
fn tiny_clouds_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.xyz");
    let out = out.to_str().unwrap();
    let two = write(dir.path(), "two.xyz", "0 0 0\n1 0 0\n");
    let three = write(dir.path(), "three.xyz", "0 0 0\n1 0 0\n0 1 0\n");
    for (input, args, problem) in [
        (
            &three,
            ["--ratio", "0.1", "--method", "fps"],
            "keeps 0 of 3 points",
        ),
        (
            &two,
            ["--ratio", "1", "--method", "tcp"],
            "TCP needs at least 3 points",
        ),
        (
            &three,
            ["--points", "4", "--method", "random"],
            "the input has only 3",
        ),
    ] {
        let mut command = vec!["simplify", input.as_str(), "-o", out];
        command.extend(args);
        let message = refused(&command);
        assert!(
            message.contains(&format!("simplifying {input}: ")) && message.contains(problem),
            "{message}"
        );
    }
}

#[test]
fn eval_names_the_cloud_that_is_too_small() {
    let dir = tempfile::tempdir().unwrap();
    let original = write(dir.path(), "original.xyz", &grid());
    let simplified = write(dir.path(), "simplified.xyz", "0 0 0\n1 0 0\n");
    let message = refused(&["eval", &original, &simplified]);
    assert!(
        message.contains(&format!(
            "evaluating {simplified} against the original {original}: invalid simplified \
             points: curvature needs at least 3 points, got 2"
        )),
        "{message}"
    );
    let empty = write(dir.path(), "empty.xyz", "");
    let message = refused(&["eval", &empty, &original]);
    assert!(
        message.contains(&format!(
            "reading the original cloud: {empty}: content: no vertices"
        )),
        "{message}"
    );
}

#[test]
fn curvature_neighbours_are_bounded() {
    let dir = tempfile::tempdir().unwrap();
    let cloud = write(dir.path(), "cloud.xyz", &grid());
    for k in ["0", "1", "257"] {
        let message = refused(&["eval", &cloud, &cloud, "--k", k]);
        assert!(
            message.contains(&format!("invalid --k: {k} is outside 2..=256")),
            "{message}"
        );
        let message = refused(&["bench", dir.path().to_str().unwrap(), "--k", k]);
        assert!(
            message.contains(&format!("invalid --k: {k} is outside 2..=256")),
            "{message}"
        );
    }
}

#[test]
fn bench_refuses_an_empty_folder_and_nonsense_ratios() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_str().unwrap();
    assert!(refused(&["bench", d]).contains("holds no cloud or mesh"));
    for ratio in ["0", "1.5", "NaN"] {
        let message = refused(&["bench", d, "--ratios", ratio]);
        assert!(message.contains("is not in (0, 1]"), "{message}");
    }
}

#[test]
fn train_counts_are_bounded_before_the_data_is_read() {
    let missing = "no-such-dataset";
    for (flag, value, expected) in [
        ("--points", "0", "invalid --points: 0 is outside 16..=65536"),
        (
            "--points",
            "1000000",
            "invalid --points: 1000000 is outside",
        ),
        ("--epochs", "0", "invalid --epochs: 0 is outside 1..=100000"),
        (
            "--clouds-per-shape",
            "1000",
            "invalid --clouds-per-shape: 1000",
        ),
        (
            "--learning-rate",
            "NaN",
            "--learning-rate NaN: must be finite and > 0",
        ),
        ("--tau", "0", "--tau 0: must be finite and > 0"),
        ("--noise=0,-0.01", "", "--noise: give finite levels σ >= 0"),
        ("--noise", "inf", "--noise: give finite levels σ >= 0"),
    ] {
        let mut args = vec!["train", missing, "-o", "w.safetensors", flag];
        if !value.is_empty() {
            args.push(value);
        }
        let message = refused(&args);
        assert!(message.contains(expected), "{flag} {value}: {message}");
    }
}

#[test]
fn bench_lists_unreadable_files_and_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "a_good.xyz", &grid());
    write(dir.path(), "b_text.obj", "this is not a mesh\n");
    write(dir.path(), "c_nan.xyz", "0 0 0\n1 nan 0\n0 1 0\n0 0 1\n");
    let d = dir.path().to_str().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_pcsimplify"))
        .args(["bench", d, "--methods", "fps", "--ratios", "0.5", "--json"])
        .output()
        .expect("the binary runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let per_file = report["per_file"].as_array().unwrap();
    assert_eq!(per_file.len(), 1);
    assert_eq!(per_file[0]["file"], "a_good.xyz");
    let skipped = report["skipped"].as_array().unwrap();
    let files: Vec<&str> = skipped
        .iter()
        .map(|s| s["file"].as_str().unwrap())
        .collect();
    assert_eq!(files, ["b_text.obj", "c_nan.xyz"]);
    assert!(
        skipped[0]["reason"]
            .as_str()
            .unwrap()
            .contains("b_text.obj")
    );
    assert!(
        skipped[1]["reason"]
            .as_str()
            .unwrap()
            .contains("non-finite"),
        "{skipped:?}"
    );

    let markdown = Command::new(env!("CARGO_BIN_EXE_pcsimplify"))
        .args(["bench", d, "--methods", "fps", "--ratios", "0.5"])
        .output()
        .expect("the binary runs");
    let text = String::from_utf8_lossy(&markdown.stdout);
    assert!(text.contains("- b_text.obj: "), "{text}");

    std::fs::remove_file(dir.path().join("a_good.xyz")).unwrap();
    let message = refused(&["bench", d, "--methods", "fps"]);
    assert!(message.contains("no file in"), "{message}");
    assert!(
        message.contains("2 skipped; first: b_text.obj"),
        "{message}"
    );
}
