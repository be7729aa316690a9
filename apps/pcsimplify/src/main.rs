//! `pcsimplify`: simplify and evaluate point clouds (thesis chapter 5).
//!
//! Thin by design: argument parsing and output live here, every computation lives in the
//! meshgnn crates. Each subcommand is one module with an `Args` struct and `run`.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod eval;

/// Simplify and evaluate point clouds (PLY, OBJ, XYZ; meshes are read as their vertices).
#[derive(Parser, Debug)]
#[command(name = "pcsimplify", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// CD, NC, CE, RE and SDM of a simplified cloud against its original (thesis ch. 5.4).
    Eval(eval::EvalArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Eval(args) => eval::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("pcsimplify: {error:#}");
            ExitCode::FAILURE
        }
    }
}
