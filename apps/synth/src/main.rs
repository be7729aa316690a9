//! `synth`: writes the synthetic meshgnn datasets as folder datasets (meshes + `dataset.json`),
//! with a progress bar and an optional PNG contact sheet. All computation lives in
//! `meshgnn-data`; this binary parses arguments, reports progress and writes files.
//!
//! ```text
//! synth hands  -n 1200 --seed 0 -o data/hands  [--preview hands.png]
//! synth faces  -n 60   --seed 0 -o data/faces  [--preview faces.png]   (--full: 180 subjects)
//! synth shapes         --seed 0 -o data/shapes [--preview shapes.png]
//! ```

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use meshgnn_data::{
    Expression, ExpressionLabels, FaceIdentity, FaceSetConfig, FaceTemplate, HandPose,
    HandSetConfig, HandShape, HandTemplate, LidarConfig, MAX_FACE_SUBJECTS, MAX_HAND_SUBJECTS,
    MAX_LIDAR_SCENES, MAX_SHAPE_RESOLUTION, MAX_SHAPES_PER_FAMILY, Manifest, SequenceStats,
    ShapeFamily, View, contact_sheet, hand_splits, lidar_scene, noisy_scan, shape_mesh,
    write_manifest, write_png,
};
use meshgnn_geometry::{TriMesh, check_count, stderr_line, write_mesh, write_point_cloud};
use rayon::prelude::*;
use serde_json::json;

/// Subjects of `synth faces --full`: 4DFAB's 180 (153 train / 27 test, thesis ch. 4.4.1).
const FULL_FACE_SUBJECTS: usize = 180;

/// Synthetic datasets for meshgnn.
#[derive(Parser)]
#[command(version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Registered hands of subjects aged 1-81 in random poses (thesis ch. 3).
    Hands {
        /// Number of subjects (one mesh each).
        #[arg(short = 'n', long, default_value_t = 1200)]
        count: usize,
        /// Seed of every random choice.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Output folder.
        #[arg(short, long)]
        output: PathBuf,
        /// Catmull–Clark levels: 1: 717, 2: 2 833, 3: 11 265 vertices.
        #[arg(long, default_value_t = meshgnn_data::DEFAULT_HAND_SUBDIVISIONS)]
        subdivisions: u32,
        /// Flat rest pose for every subject (shape variation only).
        #[arg(long)]
        pose_free: bool,
        /// Write a PNG contact sheet of the first 8 hands.
        #[arg(long)]
        preview: Option<PathBuf>,
    },
    /// 4D faces: six expression sequences per subject (thesis ch. 4, 4DFAB-like). The default
    /// 60 subjects (51 train / 9 test, ≈ 1.1 GB) train on a laptop; `--full` writes the
    /// thesis-size set (180 subjects, 153 / 27, ≈ 3.4 GB).
    Faces {
        /// Number of subjects (27 of 180 held out for test, proportionally otherwise).
        #[arg(short = 'n', long, default_value_t = 60, conflicts_with = "full")]
        count: usize,
        /// The thesis-size set: 180 subjects, 153 train / 27 test (as 4DFAB, ch. 4.4.1).
        #[arg(long)]
        full: bool,
        /// Seed of every random choice.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Output folder.
        #[arg(short, long)]
        output: PathBuf,
        /// Keep every k-th frame of the 60-100 frame sequences.
        #[arg(long, default_value_t = 5)]
        frame_step: usize,
        /// Write a PNG contact sheet: the neutral face and the six apex frames of the first
        /// two subjects (keep --frame-step at most 5 so every apex plateau has a frame).
        #[arg(long)]
        preview: Option<PathBuf>,
    },
    /// Simplification shapes (CAD, creatures, noisy scans, LiDAR clouds; ch. 5-6).
    Shapes {
        /// Seed of every random choice.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Output folder.
        #[arg(short, long)]
        output: PathBuf,
        /// Shapes per family (5 families).
        #[arg(long, default_value_t = 8)]
        per_family: usize,
        /// Grid cells along the longest side (96 ≈ 30-90k faces).
        #[arg(long, default_value_t = 96)]
        resolution: usize,
        /// Gaussian noise σ of the noisy variants, as a fraction of the bounding-sphere radius.
        #[arg(long, default_value_t = 0.005)]
        noise: f64,
        /// LiDAR scenes to write (≈2 M points each).
        #[arg(long, default_value_t = 1)]
        lidar: usize,
        /// Write a PNG contact sheet (one shape per family and a noisy one).
        #[arg(long)]
        preview: Option<PathBuf>,
    },
}

fn progress(len: usize, what: &str) -> ProgressBar {
    let bar = ProgressBar::new(len as u64);
    if let Ok(style) = ProgressStyle::with_template(
        "{msg:>8} [{elapsed_precise}] {wide_bar} {pos}/{len} ({eta} left)",
    ) {
        bar.set_style(style);
    }
    bar.set_message(what.to_string());
    bar
}

fn create_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))
}

fn preview(path: &Option<PathBuf>, meshes: &[TriMesh], view: View) -> Result<()> {
    preview_sheet(path, meshes, 4, 256, view)
}

fn preview_sheet(
    path: &Option<PathBuf>,
    meshes: &[TriMesh],
    columns: u32,
    tile: u32,
    view: View,
) -> Result<()> {
    if let Some(path) = path {
        write_png(path, &contact_sheet(meshes, columns, tile, view)?)?;
        stderr_line!("preview: {}", path.display());
    }
    Ok(())
}

fn hands(
    count: usize,
    seed: u64,
    output: &Path,
    subdivisions: u32,
    pose_free: bool,
    preview_path: &Option<PathBuf>,
) -> Result<()> {
    check_count(
        "-n",
        count,
        1..=MAX_HAND_SUBJECTS,
        "one mesh file per subject",
    )?;
    let cfg = HandSetConfig {
        count,
        seed,
        subdivisions,
        articulated: !pose_free,
        ..Default::default()
    };
    cfg.validate()?;
    let template = HandTemplate::new(subdivisions)?;
    create_dir(output)?;
    let rest = template.generate(&HandShape::adult(), &HandPose::rest())?;
    write_mesh(output.join("template.ply"), &rest)?;
    let bar = progress(count, "hands");
    let samples = (0..count)
        .into_par_iter()
        .map(|i| {
            let mut sample = cfg.sample(&template, i)?;
            let mesh = TriMesh::new(
                std::mem::take(&mut sample.vertices),
                template.triangles().to_vec(),
            )?;
            write_mesh(output.join(format!("{}.ply", sample.name)), &mesh)?;
            bar.inc(1);
            Ok((sample, (i < 8).then_some(mesh)))
        })
        .collect::<Result<Vec<_>>>()?;
    bar.finish();
    let labels = samples
        .iter()
        .map(|(s, _)| {
            let label = json!({
                "age": s.shape.age,
                "hand_length_mm": s.shape.hand_length(),
                "gesture": s.gesture.name(),
                "kept_thumb_fingers_wrist": s.kept,
                "flexion_rad": s.pose.flexion,
                "spread_rad": s.pose.spread,
                "opposition_rad": s.pose.opposition,
                "wrist_rad": s.pose.wrist,
            });
            (format!("{}.ply", s.name), label)
        })
        .collect();
    let (samples, firsts): (Vec<_>, Vec<_>) = samples.into_iter().unzip();
    let manifest = Manifest {
        format_version: 1,
        description: format!(
            "synthetic hands: {count} subjects, seed {seed}, {} vertices, millimetres, {}",
            template.vertex_count(),
            if pose_free {
                "rest pose"
            } else {
                "random poses"
            }
        ),
        template: Some("template.ply".into()),
        splits: hand_splits(&samples, "ply"),
        labels,
    };
    write_manifest(output, &manifest)?;
    let firsts: Vec<TriMesh> = firsts.into_iter().flatten().collect();
    // From the palm side, three-quarter: fists, pinches and the thumb are seen.
    preview(
        preview_path,
        &firsts,
        View {
            yaw: 155.0,
            pitch: -30.0,
            wireframe: false,
        },
    )
}

fn faces(
    count: usize,
    seed: u64,
    output: &Path,
    frame_step: usize,
    preview_path: &Option<PathBuf>,
) -> Result<()> {
    check_count(
        "-n",
        count,
        1..=MAX_FACE_SUBJECTS,
        "about 100 mesh files per subject",
    )?;
    check_count(
        "--frame-step",
        frame_step,
        1..=100,
        "keep every k-th frame of the 60-100 frame sequences",
    )?;
    let cfg = FaceSetConfig {
        subjects: count,
        seed,
        frame_step,
    };
    create_dir(output)?;
    let template = FaceTemplate::default();
    let tri = template.triangles().to_vec();
    let mean = TriMesh::new(template.neutral(&FaceIdentity::mean()), tri.clone())?;
    write_mesh(output.join("template.ply"), &mean)?;
    let bar = progress(count, "faces");
    type Frame = (String, &'static str, Expression, usize, f64);
    type Done = (
        Vec<Frame>,
        Vec<(Expression, f64, f64)>,
        String,
        &'static str,
        Vec<TriMesh>,
    );
    let subjects = (0..count)
        .into_par_iter()
        .map(|i| -> Result<Done> {
            let s = cfg.subject(&template, i)?;
            let neutral = format!("{}_neutral.ply", s.name);
            let neutral_mesh = TriMesh::new(s.neutral.clone(), tri.clone())?;
            write_mesh(output.join(&neutral), &neutral_mesh)?;
            let mut frames = Vec::new();
            let mut stats = Vec::new();
            let mut apex = Vec::new();
            if i < PREVIEW_SUBJECTS {
                apex.push(neutral_mesh);
            }
            for q in &s.sequences {
                stats.push((q.expression, q.mean_abs_deformation, q.extremeness));
                let best = q
                    .motion
                    .iter()
                    .enumerate()
                    .max_by(|a, b| a.1.total_cmp(b.1))
                    .map(|(k, _)| k);
                for (k, (frame, verts)) in q.frame_indices.iter().zip(&q.frames).enumerate() {
                    let name = format!("{}_{}_f{frame:03}.ply", s.name, q.expression.name());
                    let mesh = TriMesh::new(verts.clone(), tri.clone())?;
                    write_mesh(output.join(&name), &mesh)?;
                    if i < PREVIEW_SUBJECTS && Some(k) == best {
                        apex.push(mesh);
                    }
                    frames.push((name, s.split, q.expression, *frame, q.motion[k]));
                }
            }
            bar.inc(1);
            Ok((frames, stats, neutral, s.split, apex))
        })
        .collect::<Result<Vec<_>>>()?;
    bar.finish();
    // eq. 4.3's intensity scales over every sequence of every subject
    let sequence_labels = ExpressionLabels::new(
        &subjects
            .iter()
            .map(|s| {
                s.1.iter()
                    .map(
                        |&(expression, mean_abs_deformation, extremeness)| SequenceStats {
                            expression,
                            mean_abs_deformation,
                            extremeness,
                        },
                    )
                    .collect::<Vec<_>>()
            })
            .collect::<Vec<_>>(),
    )?;
    let mut splits: BTreeMap<String, Vec<String>> = BTreeMap::new();
    let mut labels = BTreeMap::new();
    let mut previews = Vec::new();
    for (subject, (frames, _, neutral, split, apex)) in subjects.into_iter().enumerate() {
        splits
            .entry(split.to_string())
            .or_default()
            .push(neutral.clone());
        labels.insert(
            neutral,
            json!({ "subject": subject, "expression": "neutral" }),
        );
        for (name, split, e, frame, motion) in frames {
            let l = sequence_labels.label(subject, e, motion)?;
            labels.insert(
                name.clone(),
                json!({
                    "subject": subject, "expression": e.name(), "frame": frame,
                    "motion": motion, "intensity": l.intensity, "label": l.label,
                    "mean_abs_deformation_mm": l.mean_abs_deformation,
                    "extremeness": l.extremeness,
                }),
            );
            splits.entry(split.to_string()).or_default().push(name);
        }
        previews.extend(apex);
    }
    let manifest = Manifest {
        format_version: 1,
        description: format!(
            "synthetic 4D faces: {count} subjects × 6 expressions, seed {seed}, every {frame_step}th frame, millimetres; label = one-hot × motion × s_i (eq. 4.3)"
        ),
        template: Some("template.ply".into()),
        splits,
        labels,
    };
    write_manifest(output, &manifest)?;
    let (files, bytes) = folder_size(output)?;
    stderr_line!(
        "faces: {count} subjects ({} train / {} test), {files} files, {:.2} GB in {}",
        count - cfg.test_subjects(),
        cfg.test_subjects(),
        bytes as f64 / 1e9,
        output.display()
    );
    preview_sheet(
        preview_path,
        &previews,
        1 + Expression::ALL.len() as u32,
        320,
        View {
            yaw: -15.0,
            pitch: 5.0,
            wireframe: false,
        },
    )
}

/// Subjects whose neutral face and six apex frames make the `faces --preview` sheet.
const PREVIEW_SUBJECTS: usize = 2;

/// Number of files directly in `dir` and their total size in bytes.
fn folder_size(dir: &Path) -> Result<(usize, u64)> {
    let mut files = 0;
    let mut bytes = 0;
    for entry in std::fs::read_dir(dir).with_context(|| format!("listing {}", dir.display()))? {
        let meta = entry?.metadata()?;
        if meta.is_file() {
            files += 1;
            bytes += meta.len();
        }
    }
    Ok((files, bytes))
}

#[allow(clippy::too_many_arguments)]
fn shapes(
    seed: u64,
    output: &Path,
    per_family: usize,
    resolution: usize,
    noise: f64,
    lidar: usize,
    preview_path: &Option<PathBuf>,
) -> Result<()> {
    check_count(
        "--per-family",
        per_family,
        1..=MAX_SHAPES_PER_FAMILY,
        "shapes of each of the 5 families",
    )?;
    check_count(
        "--resolution",
        resolution,
        8..=MAX_SHAPE_RESOLUTION,
        "grid cells along the longest side; memory grows with its cube",
    )?;
    check_count(
        "--lidar",
        lidar,
        0..=MAX_LIDAR_SCENES,
        "2 M points per scene",
    )?;
    if !(noise >= 0.0 && noise.is_finite()) {
        anyhow::bail!("--noise {noise}: must be a finite fraction of the sphere radius >= 0");
    }
    create_dir(output)?;
    let jobs: Vec<(ShapeFamily, usize)> = ShapeFamily::ALL
        .iter()
        .flat_map(|&f| (0..per_family).map(move |i| (f, i)))
        .collect();
    let bar = progress(jobs.len() + lidar, "shapes");
    let written = jobs
        .par_iter()
        .enumerate()
        .map(|(k, &(family, i))| -> Result<_> {
            let mesh = shape_mesh(
                family,
                seed.wrapping_mul(1000).wrapping_add(k as u64),
                resolution,
            )?;
            let name = format!("{}_{i:02}.ply", family.name());
            write_mesh(output.join(&name), &mesh)?;
            let noisy = noisy_scan(&mesh, noise, seed ^ (k as u64 + 1))?;
            let noisy_name = format!("{}_{i:02}_noisy.ply", family.name());
            write_mesh(output.join(&noisy_name), &noisy)?;
            bar.inc(1);
            let keep = (i == 0).then(|| (mesh.clone(), noisy.clone()));
            Ok((family, name, noisy_name, mesh.face_count(), keep))
        })
        .collect::<Result<Vec<_>>>()?;
    let mut splits: BTreeMap<String, Vec<String>> = BTreeMap::new();
    let mut labels = BTreeMap::new();
    let mut previews = Vec::new();
    for (family, name, noisy_name, faces, keep) in written {
        splits
            .entry(family.split().to_string())
            .or_default()
            .push(name.clone());
        splits
            .entry(format!("{}-noisy", family.split()))
            .or_default()
            .push(noisy_name.clone());
        labels.insert(name, json!({ "family": family.name(), "faces": faces }));
        labels.insert(
            noisy_name,
            json!({ "family": family.name(), "noise_sigma_of_radius": noise }),
        );
        if let Some((m, n)) = keep {
            previews.push(m);
            if previews.len() < 6 {
                previews.push(n);
            }
        }
    }
    for s in 0..lidar {
        let cloud = lidar_scene(&LidarConfig {
            seed: seed.wrapping_add(s as u64),
            ..Default::default()
        })?;
        let name = format!("lidar_{s:02}.ply");
        write_point_cloud(output.join(&name), &cloud)?;
        splits.entry("lidar".into()).or_default().push(name.clone());
        labels.insert(name, json!({ "points": cloud.len(), "units": "metres" }));
        bar.inc(1);
    }
    bar.finish();
    let manifest = Manifest {
        format_version: 1,
        description: format!(
            "simplification shapes, seed {seed}: families train = boxes, gears, creatures-a; test = fandisk, creatures-b; *-noisy: Gaussian σ = {noise} × diagonal; lidar: point clouds"
        ),
        template: None,
        splits,
        labels,
    };
    write_manifest(output, &manifest)?;
    previews.truncate(8);
    preview(preview_path, &previews, View::default())
}

fn main() -> std::process::ExitCode {
    match run(&Cli::parse()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(error) => {
            stderr_line!("synth: {error:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run(cli: &Cli) -> Result<()> {
    meshgnn_geometry::remove_temporaries_on_interrupt()
        .context("installing the interrupt handler")?;
    let start = Instant::now();
    match &cli.command {
        Command::Hands {
            count,
            seed,
            output,
            subdivisions,
            pose_free,
            preview,
        } => {
            hands(*count, *seed, output, *subdivisions, *pose_free, preview)?;
        }
        Command::Faces {
            count,
            full,
            seed,
            output,
            frame_step,
            preview,
        } => {
            let count = if *full { FULL_FACE_SUBJECTS } else { *count };
            faces(count, *seed, output, *frame_step, preview)?;
        }
        Command::Shapes {
            seed,
            output,
            per_family,
            resolution,
            noise,
            lidar,
            preview,
        } => {
            shapes(
                *seed,
                output,
                *per_family,
                *resolution,
                *noise,
                *lidar,
                preview,
            )?;
        }
    }
    stderr_line!("done in {:.1} s", start.elapsed().as_secs_f64());
    Ok(())
}
