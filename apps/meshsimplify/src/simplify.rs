//! `meshsimplify simplify IN -o OUT (--ratio R | --faces N) [--method qem] [--max-error E]
//! [--seed S] [--force] [--json]`: simplify a mesh file to a target size.
//!
//! Any format the geometry crate reads and writes (OBJ, PLY, OFF, glTF/GLB; the output format
//! follows OUT's extension, written atomically). Every argument is checked before anything is
//! written: a ratio outside (0, 1], an unknown method, an unreadable input, an unsupported
//! output extension, or OUT naming IN without `--force` exit non-zero with a message.
//!
//! `--json` prints one object with the keys `input_faces`, `output_faces`, `error`,
//! `seconds`, `stop_reason` (`error` is the largest collapse error as a distance in the input's
//! units, see `meshgnn_graph::Decimation::error_distance`).

use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use meshgnn_geometry::{InputUse, MeshFormat, OutputGuard, read_input_mesh, write_mesh};
use meshgnn_graph::{DecimationOptions, Target, decimate_with_progress};
use serde_json::json;

/// Simplification methods.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Quadric error metric edge collapse (Garland & Heckbert 1997).
    Qem,
}

/// Arguments of `meshsimplify simplify`.
#[derive(clap::Args, Debug)]
#[command(group(clap::ArgGroup::new("size").required(true).args(["ratio", "faces"])))]
pub struct SimplifyArgs {
    /// The mesh to simplify (.obj .ply .off .gltf .glb).
    pub input: PathBuf,
    /// Where to write the result; the format follows the extension.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Keep this fraction of the faces, in (0, 1].
    #[arg(short, long)]
    pub ratio: Option<f64>,
    /// Keep this many faces.
    #[arg(short, long)]
    pub faces: Option<usize>,
    /// The simplification method.
    #[arg(long, value_enum, default_value_t = Method::Qem)]
    pub method: Method,
    /// Stop before any collapse whose error exceeds this distance (input units).
    #[arg(long)]
    pub max_error: Option<f64>,
    /// Seed for randomised methods (QEM is deterministic and does not use it).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Allow the output to overwrite the input.
    #[arg(long)]
    pub force: bool,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Runs `meshsimplify simplify`.
pub fn run(args: &SimplifyArgs) -> Result<()> {
    let target = match (args.ratio, args.faces) {
        (Some(r), _) if !(r > 0.0 && r <= 1.0) => bail!("--ratio {r} is outside (0, 1]"),
        (Some(r), _) => Target::Ratio(r),
        (None, Some(n)) => Target::Faces(n),
        (None, None) => bail!("give --ratio R or --faces N"),
    };
    if let Some(e) = args.max_error
        && !(e >= 0.0 && e.is_finite())
    {
        bail!("--max-error {e} must be a finite distance >= 0");
    }
    MeshFormat::from_path(&args.output)
        .with_context(|| format!("output {}", args.output.display()))?;
    let guarded = if args.force { None } else { Some(&args.input) };
    OutputGuard::new(guarded)
        .overridable_by("--force")
        .check(&args.output)?;
    let mesh = read_input_mesh(&args.input, InputUse::Surface)?;
    check_target(&target, mesh.face_count())
        .with_context(|| format!("simplifying {}", args.input.display()))?;

    let options = DecimationOptions {
        target,
        max_error: args.max_error,
        ..Default::default()
    };
    let start = Instant::now();
    let bar = ProgressBar::hidden();
    bar.set_length(1000);
    bar.set_style(
        ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {percent}% simplifying")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mut shown = false;
    let result = match args.method {
        Method::Qem => decimate_with_progress(&mesh, &options, &mut |fraction| {
            if !shown && start.elapsed() > Duration::from_secs(1) {
                bar.set_draw_target(ProgressDrawTarget::stderr());
                shown = true;
            }
            bar.set_position((fraction.clamp(0.0, 1.0) * 1000.0) as u64);
        })?,
    };
    bar.finish_and_clear();
    let seconds = start.elapsed().as_secs_f64();
    write_mesh(&args.output, &result.mesh)
        .with_context(|| format!("writing {}", args.output.display()))?;

    if args.json {
        let summary = json!({
            "input_faces": result.input_faces,
            "output_faces": result.mesh.face_count(),
            "error": result.error_distance,
            "seconds": seconds,
            "stop_reason": result.stop_reason.as_str(),
        });
        println!("{summary}");
    } else {
        println!(
            "{}: {} faces, {} vertices -> {}: {} faces, {} vertices ({}{})",
            args.input.display(),
            result.input_faces,
            result.input_vertices,
            args.output.display(),
            result.mesh.face_count(),
            result.mesh.vertex_count(),
            result.stop_reason.as_str(),
            if result.welded { ", welded" } else { "" },
        );
        println!(
            "error {:.3e} (input units), {seconds:.3} s",
            result.error_distance
        );
    }
    Ok(())
}

/// Fails unless `target` keeps between 1 and all of the input's `faces`.
fn check_target(target: &Target, faces: usize) -> Result<()> {
    match *target {
        Target::Faces(0) => bail!("--faces 0: keep at least 1 face"),
        Target::Faces(n) if n > faces => bail!(
            "--faces {n} is more than the input's {faces} faces: choose at most {faces} \
             (or copy the file)"
        ),
        Target::Ratio(r) if (r * faces as f64).round() < 1.0 => bail!(
            "--ratio {r} keeps 0 of the input's {faces} faces: raise it to at least {:.3e}",
            1.0 / faces as f64
        ),
        _ => Ok(()),
    }
}
