//! `meshsimplify simplify IN -o OUT (--ratio R | --faces N) [--method qem] [--max-error E]
//! [--seed S] [--force] [--json]`: simplify a mesh file to a target size, or every mesh file
//! of a folder IN into the folder OUT (same names; files in parallel; a failed file never
//! stops the others, and the exit code says whether any failed).
//!
//! Any format the geometry crate reads and writes (OBJ, PLY, OFF, glTF/GLB; the output format
//! follows OUT's extension, written atomically). Every argument is checked before anything is
//! written: a ratio outside (0, 1], an unknown method, an unreadable input, an unsupported
//! output extension, or OUT naming IN without `--force` exit non-zero with a message.
//!
//! `--json` prints one object with the keys `input_faces`, `output_faces`, `error`,
//! `seconds`, `stop_reason` (`error` is the largest collapse error as a distance in the input's
//! units, see `meshgnn_graph::Decimation::error_distance`); for a folder, one such line per
//! file with `input` and `output` added, or `{"input", "failure"}` for a file that failed.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use meshgnn_geometry::{
    InputUse, MeshFormat, OutputGuard, mesh_files_in, read_input_mesh, write_mesh,
};
use meshgnn_graph::{DecimationOptions, Target, decimate_with_progress};
use rayon::prelude::*;
use serde_json::{Value, json};

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
    /// The mesh to simplify (.obj .ply .off .gltf .glb), or a folder of them.
    pub input: PathBuf,
    /// Where to write the result (the format follows the extension), or the output folder.
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

/// Runs `meshsimplify simplify` on one file, or on every mesh file of a folder.
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
    let options = DecimationOptions {
        target,
        max_error: args.max_error,
        ..Default::default()
    };
    if args.input.is_dir() {
        return run_folder(args, &options);
    }
    MeshFormat::from_path(&args.output)
        .with_context(|| format!("output {}", args.output.display()))?;
    let guarded = if args.force { None } else { Some(&args.input) };
    OutputGuard::new(guarded)
        .overridable_by("--force")
        .check(&args.output)?;
    let start = Instant::now();
    let bar = ProgressBar::hidden();
    bar.set_length(1000);
    bar.set_style(
        ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {percent}% simplifying")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mut shown = false;
    let outcome = simplify_file(&args.input, &args.output, args.method, &options, &mut |f| {
        if !shown && start.elapsed() > Duration::from_secs(1) {
            bar.set_draw_target(ProgressDrawTarget::stderr());
            shown = true;
        }
        bar.set_position((f.clamp(0.0, 1.0) * 1000.0) as u64);
    });
    bar.finish_and_clear();
    let outcome = outcome?;
    if args.json {
        println!("{}", outcome.to_json(None));
    } else {
        outcome.print(&args.input, &args.output);
    }
    Ok(())
}

/// What one simplified file reports.
struct Outcome {
    input_faces: usize,
    input_vertices: usize,
    faces: usize,
    vertices: usize,
    error: f64,
    seconds: f64,
    stop_reason: &'static str,
    welded: bool,
}

impl Outcome {
    /// The `--json` keys; a folder run adds the file paths.
    fn to_json(&self, files: Option<(&Path, &Path)>) -> Value {
        let mut value = json!({
            "input_faces": self.input_faces,
            "output_faces": self.faces,
            "error": self.error,
            "seconds": self.seconds,
            "stop_reason": self.stop_reason,
        });
        if let (Some((input, output)), Some(map)) = (files, value.as_object_mut()) {
            map.insert("input".into(), json!(input.display().to_string()));
            map.insert("output".into(), json!(output.display().to_string()));
        }
        value
    }

    fn print(&self, input: &Path, output: &Path) {
        println!(
            "{}: {} faces, {} vertices -> {}: {} faces, {} vertices ({}{})",
            input.display(),
            self.input_faces,
            self.input_vertices,
            output.display(),
            self.faces,
            self.vertices,
            self.stop_reason,
            if self.welded { ", welded" } else { "" },
        );
        println!(
            "error {:.3e} (input units), {:.3} s",
            self.error, self.seconds
        );
    }
}

/// Reads, checks, simplifies and writes one file, reporting progress in [0, 1].
fn simplify_file(
    input: &Path,
    output: &Path,
    method: Method,
    options: &DecimationOptions,
    progress: &mut dyn FnMut(f64),
) -> Result<Outcome> {
    let mesh = read_input_mesh(input, InputUse::Surface)?;
    check_target(&options.target, mesh.face_count())
        .with_context(|| format!("simplifying {}", input.display()))?;
    let start = Instant::now();
    let result = match method {
        Method::Qem => decimate_with_progress(&mesh, options, progress)
            .with_context(|| format!("simplifying {}", input.display()))?,
    };
    let seconds = start.elapsed().as_secs_f64();
    write_mesh(output, &result.mesh).with_context(|| format!("writing {}", output.display()))?;
    Ok(Outcome {
        input_faces: result.input_faces,
        input_vertices: result.input_vertices,
        faces: result.mesh.face_count(),
        vertices: result.mesh.vertex_count(),
        error: result.error_distance,
        seconds,
        stop_reason: result.stop_reason.as_str(),
        welded: result.welded,
    })
}

/// Every mesh file of the folder `args.input` into the folder `args.output` under its own
/// name, files in parallel with a progress bar over files. Every output is checked before
/// anything is written; a file that fails is reported and the others go on; the run fails
/// when any file did.
fn run_folder(args: &SimplifyArgs, options: &DecimationOptions) -> Result<()> {
    let files = mesh_files_in(&args.input)?;
    if files.is_empty() {
        bail!(
            "{} holds no mesh file (.obj .ply .off .gltf .glb)",
            args.input.display()
        );
    }
    let outputs: Vec<PathBuf> = files
        .iter()
        .map(|file| args.output.join(file.file_name().unwrap_or_default()))
        .collect();
    let guarded = if args.force { None } else { Some(&args.input) };
    let guard = OutputGuard::new(guarded).overridable_by("--force");
    for output in &outputs {
        guard.check(output)?;
    }
    std::fs::create_dir_all(&args.output)
        .with_context(|| format!("creating {}", args.output.display()))?;
    let bar = ProgressBar::new(files.len() as u64);
    bar.set_style(
        ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {pos}/{len} files")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let results: Vec<Result<Outcome>> = files
        .par_iter()
        .zip(&outputs)
        .map(|(input, output)| {
            let outcome = simplify_file(input, output, args.method, options, &mut |_| {});
            bar.inc(1);
            outcome
        })
        .collect();
    bar.finish_and_clear();
    let mut failed = 0;
    for ((input, output), result) in files.iter().zip(&outputs).zip(results) {
        match (result, args.json) {
            (Ok(outcome), true) => println!("{}", outcome.to_json(Some((input, output)))),
            (Ok(outcome), false) => outcome.print(input, output),
            (Err(error), json) => {
                failed += 1;
                let message = format!("{error:#}");
                if json {
                    let line = json!({ "input": input.display().to_string(), "failure": message });
                    println!("{line}");
                }
                eprintln!("meshsimplify: {message}");
            }
        }
    }
    if failed > 0 {
        bail!(
            "{failed} of {} mesh files in {} failed (listed above); the others were written",
            files.len(),
            args.input.display()
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
