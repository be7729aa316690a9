//! `express generate`: animates a neutral face (or the model's mean face) with an expression
//! — the onset-apex-offset curve of one expression, or a CSV curve — and writes a glTF
//! animation (morph targets, plays in any glTF viewer) or one mesh file per frame.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::Args;
use meshgnn_data::{SequenceTiming, View, contact_sheet, write_png};
use meshgnn_geometry::{
    MorphAnimation, OutputGuard, TriMesh, read_mesh, stderr_line, stdout_line, write_mesh,
    write_morph_animation,
};
use serde_json::json;

use crate::label_curve::{expression_named, parse_label_curve, timed_labels};
use crate::model::{BUNDLED_GENERATOR, load_model};

/// Arguments of `express generate`.
#[derive(Args, Debug)]
pub struct GenerateArgs {
    /// The subject's neutral face, registered to the model's template (default: the
    /// template's mean face).
    pub neutral: Option<PathBuf>,
    /// Output: a `.glb` animation, or a folder that gets one PLY per frame.
    #[arg(short, long)]
    pub output: PathBuf,
    /// The expression (happy, sad, surprise, angry, disgust, fear).
    #[arg(long, default_value = "happy", conflicts_with = "curve")]
    pub expr: String,
    /// Frames of the animation.
    #[arg(long, default_value_t = 60)]
    pub frames: usize,
    /// Last neutral frame before the onset.
    #[arg(long, default_value_t = 10)]
    pub onset: usize,
    /// First and last apex frame, `START:END`.
    #[arg(long, default_value = "20:40")]
    pub apex: String,
    /// First neutral frame after the offset.
    #[arg(long, default_value_t = 50)]
    pub offset: usize,
    /// Apex intensity in [0, 1] (`s_i` of eq. 4.3).
    #[arg(long, default_value_t = 0.8)]
    pub intensity: f64,
    /// A CSV curve `frame,expression,amplitude` instead of one expression's timing.
    #[arg(long)]
    pub curve: Option<PathBuf>,
    /// Frames per second of the animation.
    #[arg(long, default_value_t = 30.0)]
    pub fps: f64,
    /// Model weights (default: the bundled generator).
    #[arg(long)]
    pub weights: Option<PathBuf>,
    /// A PNG contact sheet of eight frames.
    #[arg(long)]
    pub preview: Option<PathBuf>,
    /// Print a JSON summary on stdout.
    #[arg(long)]
    pub json: bool,
}

fn labels(args: &GenerateArgs) -> Result<Vec<[f32; 6]>> {
    if let Some(path) = &args.curve {
        let text =
            std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        return parse_label_curve(&text, path);
    }
    let (start, end) = args
        .apex
        .split_once(':')
        .and_then(|(a, b)| Some((a.parse().ok()?, b.parse().ok()?)))
        .with_context(|| format!("--apex {}: expected START:END frames", args.apex))?;
    let timing = SequenceTiming {
        frames: args.frames,
        onset: args.onset,
        apex_start: start,
        apex_end: end,
        offset_end: args.offset,
    };
    timed_labels(expression_named(&args.expr)?, &timing, args.intensity)
}

/// True for a `.glb` output, false for a folder; an error for a single mesh or `.gltf` file.
fn is_animation(path: &Path) -> Result<bool> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match extension.as_deref() {
        Some("glb") => Ok(true),
        Some(e @ ("gltf" | "ply" | "obj" | "off" | "stl")) => bail!(
            "{}: a .{e} file cannot hold an animation; write a .glb, or name a folder for one \
             PLY per frame",
            path.display()
        ),
        _ => Ok(false),
    }
}

pub fn run(args: &GenerateArgs) -> Result<()> {
    if !(args.fps > 0.0 && args.fps.is_finite() && args.fps <= 1000.0) {
        bail!("--fps {}: must be in (0, 1000]", args.fps);
    }
    let guard = OutputGuard::new(args.neutral.iter().chain(&args.curve));
    guard.check(&args.output)?;
    let animation = is_animation(&args.output)?;
    if let Some(p) = &args.preview {
        guard.check(p)?;
    }
    let labels = labels(args)?;
    let model = load_model(args.weights.as_deref(), BUNDLED_GENERATOR)?;
    let template = model.template();
    let neutral = match &args.neutral {
        Some(path) => {
            let mesh = read_mesh(path)?;
            if mesh.vertex_count() != template.vertex_count() {
                bail!(
                    "{}: {} vertices; the face must be registered to the model's template ({} \
                     vertices, the topology of `synth faces`)",
                    path.display(),
                    mesh.vertex_count(),
                    template.vertex_count()
                );
            }
            mesh.vertices().to_vec()
        }
        None => template.vertices().to_vec(),
    };
    let started = Instant::now();
    let frames = model.generate(&labels, &neutral)?;
    let seconds = started.elapsed().as_secs_f64();
    let rest = TriMesh::new(neutral, template.triangles().to_vec())?;
    let files = if animation {
        write_morph_animation(
            &args.output,
            &MorphAnimation::new(rest.clone(), frames.clone(), args.fps)?,
        )?;
        vec![args.output.display().to_string()]
    } else {
        let paths: Vec<PathBuf> = (0..frames.len())
            .map(|k| args.output.join(format!("frame_{k:04}.ply")))
            .collect();
        for p in &paths {
            guard.check(p)?;
        }
        std::fs::create_dir_all(&args.output)
            .with_context(|| format!("creating {}", args.output.display()))?;
        for (p, f) in paths.iter().zip(&frames) {
            write_mesh(p, &rest.clone().with_vertices(f.clone())?)?;
        }
        paths.iter().map(|p| p.display().to_string()).collect()
    };
    if let Some(p) = &args.preview {
        let picks: Vec<TriMesh> = (0..8)
            .map(|k| k * (frames.len() - 1) / 7)
            .map(|k| rest.clone().with_vertices(frames[k].clone()))
            .collect::<meshgnn_geometry::Result<_>>()?;
        let view = View {
            yaw: -20.0,
            pitch: 0.0,
            wireframe: false,
        };
        write_png(p, &contact_sheet(&picks, 4, 256, view)?)?;
    }
    if args.json {
        stdout_line!(
            "{}",
            json!({"frames": frames.len(), "fps": args.fps, "seconds": seconds, "files": files,
                   "preview": args.preview.as_ref().map(|p| p.display().to_string())})
        );
    } else {
        stderr_line!(
            "generated {} frames in {:.3} s -> {}",
            frames.len(),
            seconds,
            args.output.display()
        );
    }
    Ok(())
}
