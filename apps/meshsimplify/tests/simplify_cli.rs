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

/// `meshsimplify simplify INPUT -o OUTPUT` followed by `args`.
fn simplify(input: &str, output: &str, args: &[&str]) -> Output {
    meshsimplify(&[&["simplify", input, "-o", output], args].concat())
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
        // options of the other method
        vec![
            "simplify",
            &input,
            "-o",
            out_path,
            "--ratio",
            "0.5",
            "--fill-holes",
        ],
        vec![
            "simplify",
            &input,
            "-o",
            out_path,
            "--ratio",
            "0.5",
            "--weights",
            "w.safetensors",
        ],
        vec![
            "simplify",
            &input,
            "-o",
            out_path,
            "--ratio",
            "0.5",
            "--method",
            "neural",
            "--max-error",
            "0.1",
        ],
        vec![
            "simplify",
            &input,
            "-o",
            out_path,
            "--ratio",
            "0.5",
            "--keep-positions",
        ],
        vec![
            "simplify",
            &input,
            "-o",
            out_path,
            "--ratio",
            "0.5",
            "--method",
            "neural",
            "--fill-holes",
            "100000",
        ],
        vec![
            "simplify",
            &input,
            "-o",
            out_path,
            "--ratio",
            "0.5",
            "--method",
            "neural",
            "--weights",
            "missing.safetensors",
        ],
    ] {
        let out = meshsimplify(&args);
        assert!(!out.status.success(), "{args:?} should fail");
        assert!(!String::from_utf8_lossy(&out.stderr).trim().is_empty());
        assert!(!output.exists(), "{args:?} wrote a file");
    }
}

#[test]
fn kept_vertices_stay_where_they_are_and_bad_lists_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let input = sphere_file(dir.path());
    let sphere = read_mesh(&input).unwrap();
    let keep: Vec<usize> = (0..sphere.vertex_count()).step_by(50).collect();
    let list = dir.path().join("landmarks.txt");
    let text: Vec<String> = keep.iter().map(usize::to_string).collect();
    std::fs::write(
        &list,
        format!("{}\n{}\n", text[..3].join(", "), text[3..].join(" ")),
    )
    .unwrap();
    let output = dir.path().join("small.ply");
    let (out_path, list_path) = (output.to_str().unwrap(), list.to_str().unwrap());
    let run = |extra: &[&str]| simplify(&input, out_path, &[&["--faces", "60"], extra].concat());
    let out = run(&["--keep", list_path]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let simplified = read_mesh(&output).unwrap();
    for &v in &keep {
        let p = sphere.vertices()[v];
        assert!(
            simplified.vertices().contains(&p),
            "vertex {v} moved or went"
        );
    }
    // Without the list the decimation does not keep them all.
    assert!(run(&[]).status.success());
    let free = read_mesh(&output).unwrap();
    let kept = |mesh: &meshgnn_geometry::TriMesh| {
        keep.iter()
            .filter(|&&v| mesh.vertices().contains(&sphere.vertices()[v]))
            .count()
    };
    assert!(kept(&free) < keep.len());
    std::fs::remove_file(&output).unwrap();
    let bad = dir.path().join("bad.txt");
    for (content, message) in [("3 x 7", "`x` is not a vertex index"), ("99999", "99999")] {
        std::fs::write(&bad, content).unwrap();
        let out = run(&["--keep", bad.to_str().unwrap()]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && stderr.contains(message),
            "{stderr}"
        );
        assert!(!output.exists());
    }
    let out = run(&["--keep", list_path, "--method", "neural"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("--keep applies to --method qem"));
}

#[test]
fn the_neural_method_keeps_about_the_target_vertices_edge_manifold_and_reports_watertightness() {
    let dir = tempfile::tempdir().unwrap();
    let input = sphere_file(dir.path());
    let run = |name: &str, extra: &[&str]| {
        let output = dir.path().join(name);
        let mut args = vec![
            "simplify",
            &input,
            "-o",
            output.to_str().unwrap(),
            "--ratio",
            "0.1",
            "--method",
            "neural",
            "--seed",
            "3",
            "--json",
        ];
        args.extend(extra);
        let out = meshsimplify(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{stderr}");
        let summary: Value = serde_json::from_slice(&out.stdout).unwrap();
        (
            summary,
            read_mesh(&output).unwrap(),
            std::fs::read(&output).unwrap(),
        )
    };
    let (summary, mesh, bytes) = run("a.ply", &[]);
    // 10 % of the 2 562 vertices, placed off the input's vertices (each at its region's
    // quadric optimum); with --keep-positions every one at an input vertex, the same faces.
    // Vertices cut off from their nearest drawn vertex get seeds of their own and the draw
    // shrinks by as many, so the count is near the target, not always on it: 256 for seed 3.
    assert_eq!(mesh.vertex_count(), 256);
    let input_vertices: std::collections::HashSet<[u32; 3]> = read_mesh(&input)
        .unwrap()
        .vertices()
        .iter()
        .map(|p| p.map(f32::to_bits))
        .collect();
    let at_input = |m: &meshgnn_geometry::TriMesh| {
        let bits = m.vertices().iter().map(|p| p.map(f32::to_bits));
        bits.filter(|b| input_vertices.contains(b)).count()
    };
    let (_, selected, _) = run("d.ply", &["--keep-positions"]);
    assert_eq!(selected.triangles(), mesh.triangles());
    assert_eq!(at_input(&selected), 256);
    assert!(
        at_input(&mesh) < 26,
        "{} placed vertices at input ones",
        at_input(&mesh)
    );
    assert!(summary["error"].is_null());
    assert_eq!(
        summary["output_faces"].as_u64().unwrap() as usize,
        mesh.face_count()
    );
    assert!(mesh.face_count() > 100, "{summary}");
    let report = mesh_report(&mesh);
    assert!(report.edge_manifold);
    assert_eq!(
        summary["holes"].as_u64().unwrap() as usize,
        report.boundary_loops
    );
    let (wa_raw, wa) = (
        summary["wa_raw"].as_f64().unwrap(),
        summary["wa"].as_f64().unwrap(),
    );
    assert!((0.0..=100.0).contains(&wa_raw) && (0.0..=100.0).contains(&wa));
    // Seeded: the same run writes the same bytes; hole filling only adds (faces, and a vertex
    // for a hole no triangulation of its own corners closes).
    assert_eq!(run("b.ply", &[]).2, bytes);
    let (filled, filled_mesh, _) = run("c.ply", &["--fill-holes"]);
    assert!(
        filled["holes"].as_u64() <= summary["holes"].as_u64(),
        "{filled}"
    );
    assert!(filled_mesh.face_count() >= mesh.face_count());
    assert!(mesh_report(&filled_mesh).edge_manifold);
}

#[test]
fn the_preview_shows_input_and_result_side_by_side() {
    let dir = tempfile::tempdir().unwrap();
    let input = sphere_file(dir.path());
    let output = dir.path().join("small.ply");
    let png = dir.path().join("preview.png");
    let (out_path, png_path) = (output.to_str().unwrap(), png.to_str().unwrap());
    let run = |extra: &[&str]| simplify(&input, out_path, &[&["--ratio", "0.1"], extra].concat());
    let out = run(&["--preview", png_path, "--wireframe"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    let size = |at: usize| u32::from_be_bytes(bytes[at..at + 4].try_into().unwrap());
    assert_eq!(
        (size(16), size(20)),
        (2 * 768, 768),
        "two tiles side by side"
    );
    // The preview may not replace the output or the input, nor be asked of a folder.
    std::fs::remove_file(&output).unwrap();
    for extra in [vec!["--preview", out_path], vec!["--preview", &input]] {
        let out = run(&extra);
        assert!(!out.status.success(), "{extra:?}");
        assert!(!output.exists());
    }
    let folder = dir.path().to_str().unwrap();
    let out = meshsimplify(&[
        "simplify",
        folder,
        "-o",
        out_path,
        "--ratio",
        "0.1",
        "--preview",
        png_path,
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("folder"));
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

#[test]
fn bench_scores_every_method_and_ratio_and_lists_what_it_skipped() {
    let dir = tempfile::tempdir().unwrap();
    write_mesh(dir.path().join("a_sphere.ply"), &icosphere(3)).unwrap();
    write_mesh(
        dir.path().join("b_cube.obj"),
        &meshgnn_geometry::subdivided_cube(6),
    )
    .unwrap();
    std::fs::write(dir.path().join("c_broken.obj"), "f 1 2 3\n").unwrap();
    let json_out = dir.path().join("bench.json");
    let out = meshsimplify(&[
        "bench",
        dir.path().to_str().unwrap(),
        "--ratios",
        "0.2,0.5",
        "--methods",
        "qem,neural,pc+remesh",
        "--samples",
        "2000",
        "--json",
        "--json-out",
        json_out.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: Value = serde_json::from_slice(&out.stdout).unwrap();
    let written: Value = serde_json::from_slice(&std::fs::read(&json_out).unwrap()).unwrap();
    assert_eq!(report, written);
    // 2 ratios × 3 methods, each over the two readable meshes.
    let results = report["results"].as_array().unwrap();
    assert_eq!(results.len(), 6, "{report}");
    assert!(results.iter().all(|r| r["files"] == 2));
    assert_eq!(report["per_file"].as_array().unwrap().len(), 12);
    for row in report["per_file"].as_array().unwrap() {
        for key in ["cd", "wa_raw", "wa", "le", "ne", "seconds"] {
            assert!(row[key].as_f64().unwrap() >= 0.0, "{row}");
        }
        // QEM keeps the closed inputs closed; it has no pass, so its raw WA is its WA.
        if row["method"] == "qem" {
            assert_eq!(row["wa"].as_f64().unwrap(), 0.0, "{row}");
            assert_eq!(row["wa_raw"], row["wa"], "{row}");
            assert_eq!(row["holes"], 0);
        }
    }
    let skipped = report["skipped"].as_array().unwrap();
    assert_eq!(skipped.len(), 1);
    assert_eq!(skipped[0]["file"], "c_broken.obj");
    // The neural method's options: hole filling leaves no more holes; the selected positions
    // give another surface than the placed ones.
    let neural_rows = |extra: &[&str]| {
        let mut args = vec![
            "bench",
            dir.path().to_str().unwrap(),
            "--ratios",
            "0.2,0.5",
            "--methods",
            "neural",
            "--samples",
            "2000",
            "--json",
        ];
        args.extend(extra);
        let out = meshsimplify(&args);
        assert!(out.status.success(), "{out:?}");
        let report: Value = serde_json::from_slice(&out.stdout).unwrap();
        report["per_file"].as_array().unwrap().clone()
    };
    let placed: Vec<&Value> = report["per_file"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|row| row["method"] == "neural")
        .collect();
    for (filled, placed) in neural_rows(&["--fill-holes"]).iter().zip(&placed) {
        assert_eq!(filled["file"], placed["file"]);
        assert!(filled["holes"].as_u64() <= placed["holes"].as_u64());
    }
    let selected = neural_rows(&["--keep-positions"]);
    assert!(
        selected
            .iter()
            .zip(&placed)
            .any(|(s, p)| s["cd"] != p["cd"])
    );
    // The Markdown table: a header with every metric per ratio, one line per method.
    let out = meshsimplify(&[
        "bench",
        dir.path().to_str().unwrap(),
        "--ratios",
        "0.5",
        "--methods",
        "qem,pc+remesh",
        "--samples",
        "2000",
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("| method | CD @0.5 | WA raw @0.5 | WA @0.5 | LE @0.5 | NE @0.5 | s @0.5 |"),
        "{text}"
    );
    assert!(
        text.contains("| qem |") && text.contains("| pc+remesh |"),
        "{text}"
    );
}
