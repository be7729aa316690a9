//! `express`: generate animated 3D faces from an expression label curve with the LSTM +
//! spiral mesh decoder of thesis ch. 4; train it and its blendshape baseline; Table 4.2.
//!
//! Thin by design: argument parsing, progress and file output live here, every computation
//! lives in the meshgnn crates. Each subcommand is one module with an `Args` struct and `run`.

use std::process::ExitCode;

use clap::{Parser, Subcommand};
use meshgnn_geometry::stderr_line;

mod eval;
mod face_folder;
mod generate;
mod label_curve;
mod model;
mod train;

/// Generate, train and evaluate the 4D expression generator (thesis ch. 4).
#[derive(Parser, Debug)]
#[command(name = "express", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Animate a neutral face: glTF animation (`.glb`) or one PLY per frame.
    Generate(generate::GenerateArgs),
    /// Train the generator or the blendshape baseline on a `synth faces` folder.
    Train(train::TrainArgs),
    /// Table 4.2: per-expression error of generator and baseline on the test subjects.
    Eval(eval::EvalArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if let Err(error) = meshgnn_geometry::remove_temporaries_on_interrupt() {
        stderr_line!("express: installing the interrupt handler: {error}");
        return ExitCode::FAILURE;
    }
    let result = match &cli.command {
        Command::Generate(args) => generate::run(args),
        Command::Train(args) => train::run(args),
        Command::Eval(args) => eval::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            stderr_line!("express: {error:#}");
            ExitCode::FAILURE
        }
    }
}
