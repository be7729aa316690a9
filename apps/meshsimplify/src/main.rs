//! `meshsimplify`: inspect, simplify and evaluate triangle meshes.
//!
//! Thin by design: argument parsing, progress and file output live here, every computation
//! lives in the meshgnn crates. Each subcommand is one module with an `Args` struct and `run`.

use std::process::ExitCode;

use clap::{Parser, Subcommand};
use meshgnn_geometry::stderr_line;

mod bench;
mod eval;
mod info;
mod method;
mod simplify;

/// Inspect, simplify and evaluate triangle meshes (OBJ, PLY, OFF, glTF/GLB).
#[derive(Parser, Debug)]
#[command(name = "meshsimplify", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Counts, bounding box, manifold/watertight status, boundaries, components, load time.
    Info(info::InfoArgs),
    /// Simplify a mesh to a ratio or a face count (QEM edge collapse, the neural mesh
    /// simplifier, or the point-cloud simplifier and re-meshing).
    Simplify(simplify::SimplifyArgs),
    /// Compare a simplified mesh with its original: CD, Hausdorff, NE, WA, LE, holes, manifold.
    Eval(eval::EvalArgs),
    /// Every method at every ratio on a folder of meshes, in the layout of thesis Table 6.1.
    Bench(bench::BenchArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if let Err(error) = meshgnn_geometry::remove_temporaries_on_interrupt() {
        stderr_line!("meshsimplify: installing the interrupt handler: {error}");
        return ExitCode::FAILURE;
    }
    let result = match &cli.command {
        Command::Info(args) => info::run(args),
        Command::Simplify(args) => simplify::run(args),
        Command::Eval(args) => eval::run(args),
        Command::Bench(args) => bench::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            stderr_line!("meshsimplify: {error:#}");
            ExitCode::FAILURE
        }
    }
}
