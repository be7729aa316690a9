//! `pcsimplify simplify IN -o OUT (--ratio R | --points N) [--method M] [--seed S]
//! [--triangulate] [--preview PNG] [--verbose] [--json]`: keep exactly the requested number of points of a
//! cloud or mesh (thesis ch. 5.3 and its ch. 5.5 baselines) and write them, or with
//! `--triangulate` a mesh re-built over them (ch. 5.5.3 mesh route).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use meshgnn_data::{ColoredPoints, View, point_cloud_sheet, value_colors, write_png};
use meshgnn_geometry::{
    MeshFormat, OutputGuard, PointCloud, TangentChartOptions, TriMesh, curvature_features,
    mesh_report, stdout_line, tangent_chart_triangulation, write_mesh, write_point_cloud,
};
use serde_json::{Value, json};

use crate::input::{Input, read_input};
use crate::method::{Method, Selection, load_model, select, target_count};

/// Arguments of `pcsimplify simplify`.
#[derive(clap::Args, Debug)]
pub struct SimplifyArgs {
    /// The cloud or mesh to simplify (.ply .obj .off .gltf .glb .xyz).
    pub input: PathBuf,
    /// Where to write the kept points (.ply .obj .xyz .off .glb), or the mesh with --triangulate.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Fraction of the points to keep, in (0, 1]: exactly round(ratio × #points) are kept.
    #[arg(
        short,
        long,
        conflicts_with = "points",
        required_unless_present = "points"
    )]
    pub ratio: Option<f64>,
    /// Number of points to keep.
    #[arg(short = 'n', long)]
    pub points: Option<usize>,
    /// Selection method.
    #[arg(short, long, value_enum, default_value_t = Method::DEFAULT)]
    pub method: Method,
    /// Weights of the learned method (safetensors from `pcsimplify train` for neural, from the
    /// mesh simplifier's training for sampler); default: the bundled ones.
    #[arg(long)]
    pub weights: Option<PathBuf>,
    /// Seed of every random choice (FPS start point, random sampling, latent FPS start).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Re-mesh the kept points (tangent-chart Delaunay; QEM keeps its own faces) and write
    /// a mesh.
    #[arg(long)]
    pub triangulate: bool,
    /// Write a PNG: the input and the kept points side by side, coloured by the input's
    /// curvature (eq. 5.3's K̄, blue flat → yellow curved).
    #[arg(long, value_name = "PNG")]
    pub preview: Option<PathBuf>,
    /// Print where the time went.
    #[arg(short, long)]
    pub verbose: bool,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Reads, selects, writes, reports.
pub fn run(args: &SimplifyArgs) -> Result<()> {
    let inputs = std::iter::once(&args.input).chain(&args.weights);
    let guard = OutputGuard::new(inputs);
    guard.check(&args.output)?;
    if let Some(p) = &args.preview {
        guard.check(p)?;
    }
    MeshFormat::from_path(&args.output)
        .with_context(|| format!("output {}", args.output.display()))?;
    let start = Instant::now();
    let input = read_input(&args.input)?;
    let read_seconds = start.elapsed().as_secs_f64();
    let n = input.points.len();
    let count = target_count(n, args.ratio, args.points)
        .with_context(|| format!("simplifying {}", args.input.display()))?;
    let model = load_model(args.method, args.weights.as_deref())?;
    let selection = select(args.method, &input, count, args.seed, model.as_ref())
        .with_context(|| format!("simplifying {}", args.input.display()))?;
    let kept = kept_cloud(&input, &selection)?;
    let mut report = json!({
        "input": args.input.display().to_string(),
        "output": args.output.display().to_string(),
        "method": args.method.name(),
        "seed": args.seed,
        "input_points": n,
        "kept_points": selection.indices.len(),
        "ratio": selection.indices.len() as f64 / n as f64,
        "read_seconds": read_seconds,
        "seconds": selection.seconds(),
        "timings": timings_json(&selection),
    });
    if args.triangulate {
        let t = Instant::now();
        let mesh = triangulate(&selection, &kept)
            .with_context(|| format!("simplifying {}", args.input.display()))?;
        let triangulate_seconds = t.elapsed().as_secs_f64();
        let r = mesh_report(&mesh);
        write_mesh(&args.output, &mesh)
            .with_context(|| format!("writing {}", args.output.display()))?;
        report["triangulation"] = json!({
            "seconds": triangulate_seconds,
            "faces": r.faces,
            "holes": r.boundary_loops,
            "watertight": r.watertight,
            "edge_manifold": r.edge_manifold,
            "vertex_manifold": r.vertex_manifold,
        });
    } else {
        write_point_cloud(&args.output, &kept)
            .with_context(|| format!("writing {}", args.output.display()))?;
    }
    if let Some(p) = &args.preview {
        write_preview(p, &input, &selection, &kept)
            .with_context(|| format!("writing the preview {}", p.display()))?;
        report["preview"] = json!(p.display().to_string());
    }
    if args.json {
        stdout_line!("{report}");
    } else {
        print_text(&report, &selection, args.verbose);
    }
    Ok(())
}

/// The kept points (and their normals, when the input has them), in selection order.
fn kept_cloud(input: &Input, selection: &Selection) -> Result<PointCloud> {
    let indices = &selection.indices;
    let pick = |values: &[[f32; 3]]| -> Result<Vec<[f32; 3]>> {
        indices
            .iter()
            .map(|&i| {
                values
                    .get(i as usize)
                    .copied()
                    .with_context(|| format!("selected index {i} is out of range"))
            })
            .collect()
    };
    let cloud = PointCloud::new(match &selection.points {
        Some(points) => points.clone(),
        None => pick(&input.points)?,
    })?;
    Ok(match &input.normals {
        Some(normals) => cloud.with_normals(pick(normals)?)?,
        None => cloud,
    })
}

/// The mesh written by `--triangulate`: the method's own mesh (QEM's), else the tangent-chart
/// triangulation of the kept points (input normals orient it when present).
fn triangulate(selection: &Selection, kept: &PointCloud) -> Result<TriMesh> {
    if let Some(mesh) = &selection.mesh {
        return Ok(mesh.clone());
    }
    let r = tangent_chart_triangulation(
        kept.points(),
        kept.normals(),
        &TangentChartOptions::default(),
    )
    .context("triangulating the kept points")?;
    Ok(r.mesh)
}

/// Neighbours of the preview's curvature (eq. 5.1-5.3), as in the simplifier's features.
const PREVIEW_NEIGHBOURS: usize = 16;

/// The `--preview` sheet: input and kept points in one framing, each kept point in the
/// colour of the input point it came from.
fn write_preview(
    path: &std::path::Path,
    input: &Input,
    selection: &Selection,
    kept: &PointCloud,
) -> Result<()> {
    let n = input.points.len();
    let colors = match n {
        0..=2 => vec![[0.6; 3]; n],
        _ => value_colors(
            &curvature_features(&input.points, PREVIEW_NEIGHBOURS.min(n - 1))?.mean_curvature,
        ),
    };
    let kept_colors: Vec<[f64; 3]> = selection
        .indices
        .iter()
        .map(|&i| colors.get(i as usize).copied().unwrap_or([0.6; 3]))
        .collect();
    let sheet = point_cloud_sheet(
        &[
            ColoredPoints {
                points: &input.points,
                colors: &colors,
            },
            ColoredPoints {
                points: kept.points(),
                colors: &kept_colors,
            },
        ],
        PREVIEW_TILE,
        View::default(),
    )?;
    Ok(write_png(path, &sheet)?)
}

/// Pixels per side of each preview tile.
const PREVIEW_TILE: u32 = 640;

fn timings_json(selection: &Selection) -> Value {
    Value::Object(
        selection
            .timings
            .iter()
            .map(|(stage, s)| ((*stage).to_string(), json!(s)))
            .collect(),
    )
}

fn print_text(report: &Value, selection: &Selection, verbose: bool) {
    stdout_line!(
        "{}: kept {} of {} points ({:.2} %) with {} → {}",
        report["input"].as_str().unwrap_or_default(),
        report["kept_points"],
        report["input_points"],
        100.0 * report["ratio"].as_f64().unwrap_or_default(),
        report["method"].as_str().unwrap_or_default(),
        report["output"].as_str().unwrap_or_default(),
    );
    if let Some(t) = report.get("triangulation") {
        stdout_line!(
            "triangulated: {} faces, {} holes, watertight {}, edge-manifold {}",
            t["faces"],
            t["holes"],
            t["watertight"],
            t["edge_manifold"]
        );
    }
    if verbose {
        stdout_line!(
            "read      {:>9.4} s",
            report["read_seconds"].as_f64().unwrap_or_default()
        );
        for (stage, seconds) in &selection.timings {
            stdout_line!("{stage:<9} {seconds:>9.4} s");
        }
        if let Some(t) = report.get("triangulation") {
            stdout_line!(
                "triangulate {:>7.4} s",
                t["seconds"].as_f64().unwrap_or_default()
            );
        }
    }
}
