//! `pcsimplify`: simplify and evaluate point clouds (thesis chapter 5): `simplify`, `bench`,
//! `eval`. See docs/pcsimplify.md.
//!
//! Thin by design: argument parsing and output live here, every computation lives in the
//! meshgnn crates. Each subcommand is one module with an `Args` struct and `run`.

use std::process::ExitCode;

use clap::{Parser, Subcommand};
use meshgnn_geometry::stderr_line;

mod bench;
mod eval;
mod input;
mod method;
mod simplify;
mod train;

/// Simplify and evaluate point clouds (PLY, OBJ, XYZ; meshes are read as their vertices).
#[derive(Parser, Debug)]
#[command(name = "pcsimplify", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Keep exactly round(ratio × N) points of a cloud or mesh (neural or a classical method).
    Simplify(simplify::SimplifyArgs),
    /// Every method × ratio on a folder, Table 5.1 layout (CD, NC, CE, RE, SDM).
    Bench(bench::BenchArgs),
    /// Train the learned simplifier on a `synth shapes` folder (thesis ch. 5.6).
    Train(train::TrainArgs),
    /// CD, NC, CE, RE and SDM of a simplified cloud against its original (thesis ch. 5.4).
    Eval(eval::EvalArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if let Err(error) = meshgnn_geometry::remove_temporaries_on_interrupt() {
        stderr_line!("pcsimplify: installing the interrupt handler: {error}");
        return ExitCode::FAILURE;
    }
    let result = match &cli.command {
        Command::Simplify(args) => simplify::run(args),
        Command::Bench(args) => bench::run(args),
        Command::Train(args) => train::run(args),
        Command::Eval(args) => eval::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            stderr_line!("pcsimplify: {error:#}");
            ExitCode::FAILURE
        }
    }
}
