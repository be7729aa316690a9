//! End-to-end tests of what `pcsimplify` writes: no output replaces an input (the output
//! guard), an interrupted write leaves neither a temporary file nor a partial output, and the
//! temporary files of a killed run are removed by the next one.
#![allow(clippy::expect_used, clippy::unwrap_used, clippy::panic)]

use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use meshgnn_geometry::{PointCloud, icosphere, write_mesh, write_point_cloud};

fn pcsimplify(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pcsimplify"))
        .args(args)
        .output()
        .expect("the binary runs")
}

fn text(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// Asserts a refusal: non-zero exit, one line naming both paths, nothing changed.
fn assert_refused(out: &Output, output: &str, input: &str) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert!(stderr.contains("refusing to write"), "{stderr}");
    assert!(
        stderr.contains(output) && stderr.contains(input),
        "{stderr}"
    );
    assert!(stderr.contains("write to another path"), "{stderr}");
}

#[test]
fn bench_json_out_onto_a_benchmarked_mesh_is_refused_and_the_mesh_kept() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = dir.path().join("mesh.obj");
    write_mesh(&mesh, &icosphere(2)).unwrap();
    let before = std::fs::read(&mesh).unwrap();
    let out = pcsimplify(&["bench", text(dir.path()), "--json-out", text(&mesh)]);
    assert_refused(&out, text(&mesh), text(&mesh));
    assert_eq!(std::fs::read(&mesh).unwrap(), before, "mesh untouched");
}

#[cfg(unix)]
#[test]
fn simplify_onto_a_link_to_the_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("sphere.ply");
    write_mesh(&input, &icosphere(2)).unwrap();
    let before = std::fs::read(&input).unwrap();
    let soft = dir.path().join("soft.ply");
    std::os::unix::fs::symlink(&input, &soft).unwrap();
    let hard = dir.path().join("hard.ply");
    std::fs::hard_link(&input, &hard).unwrap();
    for output in [&soft, &hard] {
        let out = pcsimplify(&[
            "simplify",
            text(&input),
            "-o",
            text(output),
            "--ratio",
            "0.5",
            "--method",
            "random",
        ]);
        assert_refused(&out, text(output), text(&input));
    }
    assert_eq!(std::fs::read(&input).unwrap(), before, "input untouched");
}

/// The PID of a process that has exited (and been reaped).
fn dead_pid() -> u32 {
    let mut child = Command::new("true").spawn().unwrap();
    let pid = child.id();
    child.wait().unwrap();
    pid
}

/// Names in `dir` that look like temporary outputs.
fn temporaries(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|name| name.contains(".tmp-"))
        .collect()
}

#[cfg(target_os = "linux")]
#[test]
fn the_next_run_removes_and_reports_a_killed_runs_temporary() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("sphere.ply");
    write_mesh(&input, &icosphere(2)).unwrap();
    let output = dir.path().join("out.obj");
    let stale_name = format!(".out.obj.tmp-{}-0", dead_pid());
    std::fs::write(dir.path().join(&stale_name), "half a mesh").unwrap();
    let out = pcsimplify(&[
        "simplify",
        text(&input),
        "-o",
        text(&output),
        "--ratio",
        "0.5",
        "--method",
        "random",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(temporaries(dir.path()).is_empty());
    assert!(output.exists());
    let report: Vec<_> = stderr.lines().filter(|l| l.contains(&stale_name)).collect();
    assert_eq!(report.len(), 1, "{stderr}");
    assert!(report[0].contains("stale temporary"), "{stderr}");
}

/// SIGINT and SIGTERM while a large output is being written: the process exits with 130, its
/// temporary file is removed and the output path never appears.
#[cfg(unix)]
#[test]
fn an_interrupted_write_leaves_no_temporary_and_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("cloud.ply");
    // 3 M points: a ≈100 MB .xyz output whose write and fsync take far longer than the poll
    let points: Vec<[f32; 3]> = (0..3_000_000u32)
        .map(|i| {
            let t = i as f32 * 1e-6;
            [t.sin() * 100.0, t.cos() * 100.0, t * 0.5]
        })
        .collect();
    write_point_cloud(&input, &PointCloud::new(points).unwrap()).unwrap();
    for signal in ["-INT", "-TERM"] {
        let output = dir.path().join("out.xyz");
        let mut child = Command::new(env!("CARGO_BIN_EXE_pcsimplify"))
            .args([
                "simplify",
                text(&input),
                "-o",
                text(&output),
                "--ratio",
                "1",
                "--method",
                "random",
            ])
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let started = Instant::now();
        while temporaries(dir.path()).is_empty() {
            assert!(
                started.elapsed() < Duration::from_secs(120),
                "no temporary file appeared"
            );
            assert!(child.try_wait().unwrap().is_none(), "finished too early");
            std::thread::sleep(Duration::from_millis(1));
        }
        let killed = Command::new("kill")
            .args([signal, &child.id().to_string()])
            .status()
            .unwrap();
        assert!(killed.success());
        let out = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(130), "{signal}: {stderr}");
        assert!(stderr.contains("interrupted"), "{signal}: {stderr}");
        assert!(temporaries(dir.path()).is_empty(), "{signal}");
        assert!(!output.exists(), "{signal}: a partial output was left");
    }
}

#[test]
fn preview_shows_input_and_kept_points_coloured_by_curvature() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("cube.ply");
    // flat faces (low curvature, blue) meeting at edges (high curvature, yellow)
    let cube = meshgnn_geometry::subdivided_cube(12);
    write_point_cloud(&input, &PointCloud::new(cube.vertices().to_vec()).unwrap()).unwrap();
    let (output, preview) = (dir.path().join("kept.ply"), dir.path().join("p.png"));
    let out = pcsimplify(&[
        "simplify",
        text(&input),
        "-o",
        text(&output),
        "--ratio",
        "0.1",
        "--method",
        "fps",
        "--preview",
        text(&preview),
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(report["preview"], text(&preview));
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(&preview).unwrap(),
    ));
    let mut reader = decoder.read_info().unwrap();
    let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut pixels).unwrap();
    assert_eq!((info.width, info.height), (1280, 640));
    let tile = |x0: usize| {
        let (mut blue, mut yellow, mut painted) = (0, 0, 0);
        for y in 0..640 {
            for x in x0..x0 + 640 {
                let i = (y * 1280 + x) * 3;
                let [r, g, b] = [pixels[i], pixels[i + 1], pixels[i + 2]].map(i32::from);
                if [r, g, b] != [250; 3] {
                    painted += 1;
                    blue += usize::from(b > g + 30);
                    yellow += usize::from(r > 120 && g > 120 && b < 80);
                }
            }
        }
        (blue, yellow, painted)
    };
    let (left, right) = (tile(0), tile(640));
    assert!(left.0 > 1000 && left.1 > 100, "input tile {left:?}");
    assert!(
        right.2 > 0 && right.2 < left.2,
        "kept {right:?}, input {left:?}"
    );
    // the preview is an output like any other: never onto the input
    let out = pcsimplify(&[
        "simplify",
        text(&input),
        "-o",
        text(&output),
        "--ratio",
        "0.1",
        "--preview",
        text(&input),
    ]);
    assert_refused(&out, text(&input), text(&input));
}
