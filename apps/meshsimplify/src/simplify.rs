//! `meshsimplify simplify IN -o OUT (--ratio R | --faces N) [--method qem|neural|pc+remesh]
//! [--max-error E] [--keep FILE] [--weights FILE] [--fill-holes [K]] [--keep-positions] [--seed S]
//! [--preview PNG [--wireframe]] [--force] [--json]`: simplify a mesh file to a target size,
//! or every mesh file of a folder IN into the folder OUT (same names; files in parallel; a
//! failed file never stops the others, and the exit code says whether any failed).
//!
//! Any format the geometry crate reads and writes (OBJ, PLY, OFF, glTF/GLB; the output format
//! follows OUT's extension, written atomically). Every argument is checked before anything is
//! written: a ratio outside (0, 1], an option the method does not take, an unreadable input or
//! weights file, an unsupported output extension, or OUT naming IN without `--force` exit
//! non-zero with a message.
//!
//! The methods are in [`crate::method`]: `neural` is the neural mesh simplifier of thesis
//! ch. 6 and `pc+remesh` the ch. 5 route (the bundled weights of each, or `--weights FILE`
//! from a training run); both select vertices, so the target becomes a vertex count.
//! `--fill-holes [K]` closes the holes of at most `K` edges (default 30) after the neural
//! method's manifold pass. The neural method moves each selected vertex to the quadric optimum
//! of the input region it stands for (`meshgnn_graph::region_quadric_placement`);
//! `--keep-positions` leaves them where the network picked them (the thesis' output).
//! `--keep FILE` (qem) never removes nor moves the input vertices the file lists (landmarks,
//! by their 0-based index in IN); the others may collapse onto them.
//!
//! `--preview PNG` (one file only) renders the input and the result side by side, shaded, with
//! the project's own rasteriser (`meshgnn_data::contact_sheet`), `--wireframe` drawing edges.
//!
//! `--json` prints one object with the keys `input_faces`, `output_faces`, `error`,
//! `seconds`, `stop_reason` (`error` is the largest collapse error as a distance in the input's
//! units, see `meshgnn_graph::Decimation::error_distance`, and `null` for the selecting
//! methods); `neural` adds `wa_raw` and `wa` (percent of edges without exactly two faces,
//! before and after the manifold pass and hole filling) and `holes` (boundary loops of the
//! output). For a folder, one such line per file with `input` and `output` added, or
//! `{"input", "failure"}` for a file that failed.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use meshgnn_data::{View, contact_sheet, write_png};
use meshgnn_geometry::{
    InputUse, MeshFormat, OutputGuard, mesh_files_in, read_input_mesh, read_vertex_list,
    stderr_line, stdout_line, write_mesh,
};
use meshgnn_graph::Target;
use rayon::prelude::*;
use serde_json::json;

use crate::method::{Method, MethodOptions, Outcome, Simplifier};

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
    /// Stop before any collapse whose error exceeds this distance (input units; qem only).
    #[arg(long)]
    pub max_error: Option<f64>,
    /// Never remove nor move these input vertices (landmarks): a text file of 0-based vertex
    /// indices separated by spaces, commas or line breaks, `#` comments (qem only, one file).
    #[arg(long, value_name = "FILE")]
    pub keep: Option<PathBuf>,
    /// Weights of the neural or point-cloud simplifier (a file its training wrote); the
    /// bundled ones when omitted (neural and pc+remesh only).
    #[arg(long)]
    pub weights: Option<PathBuf>,
    /// Close the holes of at most K boundary edges left after the manifold pass, the input's
    /// borders included (neural only; without it, only cracks away from the input's borders
    /// are filled: holes of at most 4 edges, or 8 in a piece of at least 30 faces).
    #[arg(long, value_name = "K", num_args = 0..=1, default_missing_value = "30")]
    pub fill_holes: Option<usize>,
    /// Leave the selected vertices at their input positions instead of moving each to its
    /// region's quadric optimum (neural only).
    #[arg(long)]
    pub keep_positions: bool,
    /// Seed for the selecting methods' random draws (QEM is deterministic).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Also write a PNG of the input and the result side by side (one file only).
    #[arg(long, value_name = "PNG")]
    pub preview: Option<PathBuf>,
    /// Draw the edges on the preview.
    #[arg(long, requires = "preview")]
    pub wireframe: bool,
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
    let keep = match &args.keep {
        Some(_) if args.input.is_dir() => bail!(
            "--keep names vertices of one mesh; {} is a folder",
            args.input.display()
        ),
        Some(path) => read_vertex_list(path).context("reading the --keep list")?,
        None => Vec::new(),
    };
    let options = MethodOptions {
        max_error: args.max_error,
        keep,
        fill_holes: args.fill_holes,
        keep_positions: args.keep_positions,
        weights: args.weights.as_deref(),
        seed: args.seed,
    };
    let simplifier = Simplifier::new(args.method, target, &options)?;
    if args.input.is_dir() {
        if args.preview.is_some() {
            bail!(
                "--preview renders one file; {} is a folder",
                args.input.display()
            );
        }
        return run_folder(args, &simplifier);
    }
    MeshFormat::from_path(&args.output)
        .with_context(|| format!("output {}", args.output.display()))?;
    let guarded = if args.force { None } else { Some(&args.input) };
    let guard = OutputGuard::new(guarded.into_iter().chain(&args.weights).chain(&args.keep))
        .overridable_by("--force");
    guard.check(&args.output)?;
    let preview = match &args.preview {
        Some(path) if path == &args.output => {
            bail!("--preview {} is also the output", path.display())
        }
        Some(path) => {
            // The preview never replaces an input, --force or not.
            OutputGuard::new(
                std::iter::once(&args.input)
                    .chain(&args.weights)
                    .chain(&args.keep),
            )
            .check(path)?;
            Some(Preview {
                path,
                wireframe: args.wireframe,
            })
        }
        None => None,
    };
    let start = Instant::now();
    let bar = ProgressBar::hidden();
    bar.set_length(1000);
    bar.set_style(
        ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {percent}% simplifying")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mut shown = false;
    let outcome = simplify_file(&args.input, &args.output, &simplifier, preview, &mut |f| {
        if !shown && start.elapsed() > Duration::from_secs(1) {
            bar.set_draw_target(ProgressDrawTarget::stderr());
            shown = true;
        }
        bar.set_position((f.clamp(0.0, 1.0) * 1000.0) as u64);
    });
    bar.finish_and_clear();
    let outcome = outcome?;
    if args.json {
        stdout_line!("{}", outcome.to_json(None));
    } else {
        outcome.print(&args.input, &args.output);
    }
    Ok(())
}

/// Where the side-by-side PNG goes and whether it shows edges.
#[derive(Clone, Copy)]
struct Preview<'a> {
    path: &'a Path,
    wireframe: bool,
}

/// Reads, checks, simplifies and writes one file (and its preview), reporting progress in
/// [0, 1].
fn simplify_file(
    input: &Path,
    output: &Path,
    simplifier: &Simplifier,
    preview: Option<Preview>,
    progress: &mut dyn FnMut(f64),
) -> Result<Outcome> {
    let mesh = read_input_mesh(input, InputUse::Surface)?;
    let (simplified, outcome) = simplifier
        .run(&mesh, progress)
        .with_context(|| format!("simplifying {}", input.display()))?;
    write_mesh(output, &simplified).with_context(|| format!("writing {}", output.display()))?;
    if let Some(Preview { path, wireframe }) = preview {
        let view = View {
            wireframe,
            ..View::default()
        };
        contact_sheet(&[mesh, simplified], 2, PREVIEW_TILE, view)
            .and_then(|sheet| write_png(path, &sheet))
            .with_context(|| format!("writing the preview {}", path.display()))?;
    }
    Ok(outcome)
}

/// Side of each preview tile, pixels.
const PREVIEW_TILE: u32 = 768;

/// Every mesh file of the folder `args.input` into the folder `args.output` under its own
/// name, files in parallel with a progress bar over files. Every output is checked before
/// anything is written; a file that fails is reported and the others go on; the run fails
/// when any file did.
fn run_folder(args: &SimplifyArgs, simplifier: &Simplifier) -> Result<()> {
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
            let outcome = simplify_file(input, output, simplifier, None, &mut |_| {});
            bar.inc(1);
            outcome
        })
        .collect();
    bar.finish_and_clear();
    let mut failed = 0;
    for ((input, output), result) in files.iter().zip(&outputs).zip(results) {
        match (result, args.json) {
            (Ok(outcome), true) => stdout_line!("{}", outcome.to_json(Some((input, output)))),
            (Ok(outcome), false) => outcome.print(input, output),
            (Err(error), json) => {
                failed += 1;
                let message = format!("{error:#}");
                if json {
                    let line = json!({ "input": input.display().to_string(), "failure": message });
                    stdout_line!("{line}");
                }
                stderr_line!("meshsimplify: {message}");
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
