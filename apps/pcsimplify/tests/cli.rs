//! Runs the `pcsimplify` binary on small files in a temporary folder.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::Path;
use std::process::Command;

/// Writes `points` as an XYZ file (one `x y z` line per point).
fn write_xyz(path: &Path, points: &[[f32; 3]]) {
    let text: String = points
        .iter()
        .map(|p| format!("{} {} {}\n", p[0], p[1], p[2]))
        .collect();
    std::fs::write(path, text).unwrap();
}

/// A noisy-free curved patch: points on a paraboloid over a 20×20 grid.
fn patch(step: usize) -> Vec<[f32; 3]> {
    let mut out = Vec::new();
    for i in (0..20).step_by(step) {
        for j in (0..20).step_by(step) {
            let (x, y) = (i as f32 / 19.0 - 0.5, j as f32 / 19.0 - 0.5);
            out.push([x, y, x * x - 0.5 * y * y]);
        }
    }
    out
}

#[test]
fn eval_prints_every_json_key() {
    let dir = tempfile::tempdir().unwrap();
    let original = dir.path().join("original.xyz");
    let simplified = dir.path().join("simplified.xyz");
    write_xyz(&original, &patch(1));
    write_xyz(&simplified, &patch(2));
    let out = Command::new(env!("CARGO_BIN_EXE_pcsimplify"))
        .args(["eval", "--json"])
        .arg(&original)
        .arg(&simplified)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for key in ["cd", "nc", "ce", "re", "sdm"] {
        let v = json[key]
            .as_f64()
            .unwrap_or_else(|| panic!("missing {key}: {json}"));
        assert!(v.is_finite() && v >= 0.0, "{key} = {v}");
    }
    // the simplified cloud is a strict subset: the Chamfer distance is positive
    assert!(json["cd"].as_f64().unwrap() > 0.0);
}

#[test]
fn missing_file_fails_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let original = dir.path().join("original.xyz");
    write_xyz(&original, &patch(1));
    let missing = dir.path().join("no_such_cloud.xyz");
    let out = Command::new(env!("CARGO_BIN_EXE_pcsimplify"))
        .arg("eval")
        .arg(&original)
        .arg(&missing)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("no_such_cloud.xyz"), "{stderr}");
}
