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
    for key in ["cd", "nc", "ce", "re", "sdm", "sdm_nearest"] {
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

fn pcsimplify(args: &[&std::ffi::OsStr]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_pcsimplify"))
        .args(args)
        .output()
        .unwrap()
}

/// `n × n` points on the unit sphere (latitude-longitude grid without the poles' repeats).
fn sphere_points(n: usize) -> Vec<[f32; 3]> {
    let mut out = Vec::new();
    for i in 0..n {
        let theta = std::f32::consts::PI * (i as f32 + 0.5) / n as f32;
        for j in 0..n {
            let phi = 2.0 * std::f32::consts::PI * j as f32 / n as f32;
            out.push([
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            ]);
        }
    }
    out
}

#[test]
fn simplify_writes_exactly_the_requested_count_with_every_method() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("cloud.xyz");
    write_xyz(&input, &sphere_points(20)); // 400 points
    for method in ["fps", "random", "tcp", "sampler"] {
        for (flag, value, expected) in [("--ratio", "0.1", 40), ("--points", "37", 37)] {
            let output = dir.path().join(format!("{method}_{expected}.ply"));
            let out = pcsimplify(&[
                "simplify".as_ref(),
                input.as_os_str(),
                "-o".as_ref(),
                output.as_os_str(),
                flag.as_ref(),
                value.as_ref(),
                "--method".as_ref(),
                method.as_ref(),
            ]);
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
            let cloud = meshgnn_geometry::read_point_cloud(&output).unwrap();
            assert_eq!(cloud.len(), expected, "{method} {flag} {value}");
            // Every kept point is an input point.
            let all = sphere_points(20);
            assert!(cloud.points().iter().all(|p| all.contains(p)));
        }
    }
}

#[test]
fn qem_on_a_cloud_is_refused_and_works_on_a_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let cloud = dir.path().join("cloud.xyz");
    write_xyz(&cloud, &sphere_points(10));
    let out = pcsimplify(&[
        "simplify".as_ref(),
        cloud.as_os_str(),
        "-o".as_ref(),
        dir.path().join("out.ply").as_os_str(),
        "-n".as_ref(),
        "20".as_ref(),
        "-m".as_ref(),
        "qem".as_ref(),
    ]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("needs a mesh"), "{stderr}");

    let mesh = dir.path().join("sphere.ply");
    meshgnn_geometry::write_mesh(&mesh, &meshgnn_geometry::icosphere(3)).unwrap();
    let output = dir.path().join("qem.obj");
    let out = pcsimplify(&[
        "simplify".as_ref(),
        mesh.as_os_str(),
        "-o".as_ref(),
        output.as_os_str(),
        "-n".as_ref(),
        "100".as_ref(),
        "-m".as_ref(),
        "qem".as_ref(),
        "--triangulate".as_ref(),
        "--json".as_ref(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["kept_points"], 100);
    assert_eq!(json["triangulation"]["holes"], 0);
    let written = meshgnn_geometry::read_mesh(&output).unwrap();
    assert_eq!(written.vertex_count(), 100);
    assert_eq!(written.face_count(), 196);
}

#[test]
fn triangulate_rebuilds_a_closed_sphere() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("sphere.ply");
    meshgnn_geometry::write_mesh(&input, &meshgnn_geometry::icosphere(4)).unwrap();
    let output = dir.path().join("remeshed.ply");
    let out = pcsimplify(&[
        "simplify".as_ref(),
        input.as_os_str(),
        "-o".as_ref(),
        output.as_os_str(),
        "-r".as_ref(),
        "0.2".as_ref(),
        "-m".as_ref(),
        "fps".as_ref(),
        "--triangulate".as_ref(),
        "--json".as_ref(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let mesh = meshgnn_geometry::read_mesh(&output).unwrap();
    assert_eq!(mesh.vertex_count(), 512); // round(0.2 × 2562)
    assert_eq!(json["triangulation"]["faces"], mesh.face_count());
    assert!(json["triangulation"]["edge_manifold"].as_bool().unwrap());
    // FPS on a sphere is near-uniform: the rebuild is closed.
    assert_eq!(json["triangulation"]["holes"], 0, "{json}");
}

#[test]
fn bad_targets_and_overwriting_the_input_fail_clearly() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("cloud.xyz");
    write_xyz(&input, &sphere_points(5)); // 25 points
    let cases: [(&[&str], &str); 3] = [
        (&["-r", "0.01"], "0 of 25"),
        (&["-n", "26"], "only 25"),
        (&["-r", "0"], "(0, 1]"),
    ];
    let out_path = dir.path().join("out.xyz");
    for (extra, message) in cases {
        let mut args: Vec<&std::ffi::OsStr> = vec![
            "simplify".as_ref(),
            input.as_os_str(),
            "-o".as_ref(),
            out_path.as_os_str(),
        ];
        args.extend(extra.iter().map(std::ffi::OsStr::new));
        let out = pcsimplify(&args);
        assert!(!out.status.success(), "{extra:?}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains(message), "{extra:?}: {stderr}");
    }
    let before = std::fs::read(&input).unwrap();
    let out = pcsimplify(&[
        "simplify".as_ref(),
        input.as_os_str(),
        "-o".as_ref(),
        input.as_os_str(),
        "-r".as_ref(),
        "0.5".as_ref(),
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("is the input"));
    assert_eq!(std::fs::read(&input).unwrap(), before);
}

fn results_of(json: &serde_json::Value) -> Vec<serde_json::Value> {
    json["results"].as_array().unwrap().clone()
}

#[test]
fn bench_prints_every_method_and_ratio_as_markdown_and_json() {
    let dir = tempfile::tempdir().unwrap();
    write_xyz(&dir.path().join("a.xyz"), &sphere_points(16));
    write_xyz(&dir.path().join("b.xyz"), &patch(1));
    meshgnn_geometry::write_mesh(dir.path().join("c.ply"), &meshgnn_geometry::icosphere(3))
        .unwrap();
    std::fs::write(dir.path().join("notes.txt"), "not a cloud").unwrap();
    let base = [
        "bench".as_ref(),
        dir.path().as_os_str(),
        "--ratios".as_ref(),
        "0.5,0.25".as_ref(),
        "--methods".as_ref(),
        "fps,random,tcp,qem".as_ref(),
    ];
    let out = pcsimplify(&base);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    for method in ["| fps |", "| random |", "| tcp |", "| qem |"] {
        assert_eq!(text.matches(method).count(), 2, "{method}: {text}"); // metrics and timings
    }
    for header in ["CD @0.5", "SDM @0.5", "CD @0.25", "SDM @0.25"] {
        assert!(text.contains(header), "{header}: {text}");
    }

    let json_out = dir.path().join("out").join("bench.json");
    std::fs::create_dir(dir.path().join("out")).unwrap();
    let mut args = base.to_vec();
    args.extend([std::ffi::OsStr::new("--json-out"), json_out.as_os_str()]);
    let out = pcsimplify(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("| tcp |"));
    let saved: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&json_out).unwrap()).unwrap();
    args.push("--json".as_ref());
    let out = pcsimplify(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["files"].as_array().unwrap().len(), 3);
    // Same metrics in the saved file (timings differ between runs).
    for (a, b) in results_of(&json).iter().zip(results_of(&saved)) {
        for key in [
            "method",
            "ratio",
            "files",
            "cd",
            "nc",
            "ce",
            "re",
            "sdm",
            "sdm_nearest",
        ] {
            assert_eq!(a[key], b[key], "{key}");
        }
    }
    let results = json["results"].as_array().unwrap();
    assert_eq!(results.len(), 8);
    for r in results {
        let files = if r["method"] == "qem" { 1 } else { 3 };
        assert_eq!(r["files"], files, "{r}");
        for key in ["cd", "nc", "ce", "re", "sdm", "sdm_nearest", "seconds"] {
            let v = r[key].as_f64().unwrap();
            assert!(v.is_finite() && v >= 0.0, "{key} = {v}");
        }
    }
    // qem was skipped on the two clouds at both ratios
    assert_eq!(json["skipped"].as_array().unwrap().len(), 4);
    assert_eq!(json["per_file"].as_array().unwrap().len(), 3 * 3 * 2 + 2);

    // With noise, the same selection scores worse against the clean originals.
    args.extend([
        std::ffi::OsStr::new("--noise"),
        std::ffi::OsStr::new("0.02"),
    ]);
    let out = pcsimplify(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let noisy: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(noisy["noise"], 0.02);
    let cd = |j: &serde_json::Value| j["results"][0]["cd"].as_f64().unwrap();
    assert!(cd(&noisy) > cd(&json), "{} vs {}", cd(&noisy), cd(&json));
}

#[test]
fn neural_simplify_with_weights_file_reports_the_time_split() {
    use candle_core::{DType, Device};
    use meshgnn_models::Checkpoint;
    use meshgnn_models::point_simplifier::{PointSimplifier, PointSimplifierConfig};
    let dir = tempfile::tempdir().unwrap();
    // Untrained weights: the CLI path, not the model's quality, is under test.
    let map = candle_nn::VarMap::new();
    let config = PointSimplifierConfig::default();
    PointSimplifier::new(
        candle_nn::VarBuilder::from_varmap(&map, DType::F32, &Device::Cpu),
        &config,
    )
    .unwrap();
    let tensors: Vec<(String, candle_core::Tensor)> = map
        .data()
        .lock()
        .unwrap()
        .iter()
        .map(|(k, v)| (k.clone(), v.as_tensor().clone()))
        .collect();
    let weights = dir.path().join("w.safetensors");
    Checkpoint {
        header: config.header(),
        tensors: tensors.into_iter().collect(),
    }
    .save(&weights)
    .unwrap();

    let input = dir.path().join("sphere.obj");
    meshgnn_geometry::write_mesh(&input, &meshgnn_geometry::icosphere(3)).unwrap();
    let output = dir.path().join("kept.xyz");
    let out = pcsimplify(&[
        "simplify".as_ref(),
        input.as_os_str(),
        "-o".as_ref(),
        output.as_os_str(),
        "-n".as_ref(),
        "64".as_ref(),
        "--weights".as_ref(),
        weights.as_os_str(),
        "--verbose".as_ref(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    for stage in ["knn", "projector", "selector", "attref"] {
        assert!(text.contains(stage), "{stage}: {text}");
    }
    assert_eq!(
        meshgnn_geometry::read_point_cloud(&output).unwrap().len(),
        64
    );

    let missing = dir.path().join("missing.safetensors");
    let out = pcsimplify(&[
        "simplify".as_ref(),
        input.as_os_str(),
        "-o".as_ref(),
        output.as_os_str(),
        "-n".as_ref(),
        "64".as_ref(),
        "--weights".as_ref(),
        missing.as_os_str(),
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing.safetensors"));
}
