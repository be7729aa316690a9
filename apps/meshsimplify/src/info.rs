//! `meshsimplify info FILE|DIR [--json]`: what a mesh is made of and whether it is valid.
//!
//! The `--json` keys are a stable interface for scripts (documented in docs/meshsimplify.md):
//! `file`, `vertices`, `faces`, `edges`, `bbox_min`, `bbox_max`, `edge_manifold`,
//! `vertex_manifold`, `watertight`, `boundary_edges`, `boundary_loops`, `components`,
//! `degenerate_faces`, `duplicate_faces`, `non_manifold_edges`, `misoriented_edges`,
//! `load_seconds`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Result, bail};
use meshgnn_geometry::{
    InputUse, MeshReport, mesh_files_in, mesh_report, read_input_mesh, stderr_line, stdout_line,
};
use rayon::prelude::*;
use serde_json::{Value, json};

/// Arguments of `meshsimplify info`.
#[derive(clap::Args, Debug)]
pub struct InfoArgs {
    /// A mesh file (.obj .ply .off .gltf .glb), or a folder whose mesh files are all reported.
    pub path: PathBuf,
    /// Print one JSON object per mesh (an array for a folder) instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Reports on one file, or on every mesh file of a folder in parallel. In a folder, a file
/// that cannot be read or holds no vertices is reported on stderr and the others still are;
/// the command then fails, naming how many files failed.
pub fn run(args: &InfoArgs) -> Result<()> {
    if args.path.is_dir() {
        let files = mesh_files_in(&args.path)?;
        if files.is_empty() {
            bail!(
                "{} holds no mesh file (.obj .ply .off .gltf .glb .xyz)",
                args.path.display()
            );
        }
        let results: Vec<Result<Value>> = files.par_iter().map(|file| inspect(file)).collect();
        let mut reports = Vec::with_capacity(results.len());
        let mut failed = 0;
        for result in results {
            match result {
                Ok(report) => reports.push(report),
                Err(error) => {
                    stderr_line!("meshsimplify: {error:#}");
                    failed += 1;
                }
            }
        }
        if args.json {
            stdout_line!("{}", Value::Array(reports));
        } else {
            reports.iter().for_each(print_text);
        }
        if failed > 0 {
            bail!(
                "{failed} of {} mesh files in {} could not be reported (listed above)",
                files.len(),
                args.path.display()
            );
        }
    } else {
        let report = inspect(&args.path)?;
        if args.json {
            stdout_line!("{report}");
        } else {
            print_text(&report);
        }
    }
    Ok(())
}

/// Loads `file`, times the load, and returns its report as JSON.
fn inspect(file: &Path) -> Result<Value> {
    let start = Instant::now();
    let mesh = read_input_mesh(file, InputUse::Points)?;
    let load_seconds = start.elapsed().as_secs_f64();
    let report = mesh_report(&mesh);
    Ok(to_json(file, &report, load_seconds))
}

fn to_json(file: &Path, r: &MeshReport, load_seconds: f64) -> Value {
    json!({
        "file": file.display().to_string(),
        "vertices": r.vertices,
        "faces": r.faces,
        "edges": r.edges,
        "bbox_min": r.bbox_min,
        "bbox_max": r.bbox_max,
        "edge_manifold": r.edge_manifold,
        "vertex_manifold": r.vertex_manifold,
        "watertight": r.watertight,
        "boundary_edges": r.boundary_edges,
        "boundary_loops": r.boundary_loops,
        "components": r.components,
        "degenerate_faces": r.degenerate_faces,
        "duplicate_faces": r.duplicate_faces,
        "non_manifold_edges": r.non_manifold_edges,
        "misoriented_edges": r.misoriented_edges,
        "load_seconds": load_seconds,
    })
}

fn print_text(report: &Value) {
    let field = |key: &str| report.get(key).cloned().unwrap_or(Value::Null);
    stdout_line!("{}", field("file").as_str().unwrap_or_default());
    for key in [
        "vertices",
        "faces",
        "edges",
        "bbox_min",
        "bbox_max",
        "edge_manifold",
        "vertex_manifold",
        "watertight",
        "boundary_edges",
        "boundary_loops",
        "components",
        "degenerate_faces",
        "duplicate_faces",
        "non_manifold_edges",
        "misoriented_edges",
    ] {
        stdout_line!("  {key:<19}{}", field(key));
    }
    let seconds = field("load_seconds").as_f64().unwrap_or_default();
    stdout_line!("  {:<19}{:.3} s", "load_time", seconds);
}
