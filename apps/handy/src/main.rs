//! `handy`: train, evaluate, sample and fit the Handy++ spiral hand autoencoder and its PCA
//! baseline (thesis ch. 3).
//!
//! Thin by design: argument parsing, progress and file output live here, every computation
//! lives in the meshgnn crates. Each subcommand is one module with an `Args` struct and `run`.

use std::process::ExitCode;

use clap::{Parser, Subcommand};
use meshgnn_geometry::stderr_line;

mod dataset;
mod eval;
mod fit;
mod interpolate;
mod model;
mod sample;
mod shape_folder;
mod train;

/// Train, evaluate, sample and fit the Handy++ hand model (thesis ch. 3).
#[derive(Parser, Debug)]
#[command(name = "handy", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Train Handy++ on a registered dataset (`synth hands` folder).
    Train(train::TrainArgs),
    /// Table 3.2 / 3.5 on a dataset: Handy++ vs PCA generalisation, specificity,
    /// compactness, fitting to partial noisy scans.
    Eval(eval::EvalArgs),
    /// Random hands from the model's latent Gaussian (OBJ files + PNG contact sheet).
    Sample(sample::SampleArgs),
    /// Fit the model to a scan (point cloud); prints R2S / S2R.
    Fit(fit::FitArgs),
    /// Latent interpolation between two registered hands.
    Interpolate(interpolate::InterpolateArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if let Err(error) = meshgnn_geometry::remove_temporaries_on_interrupt() {
        stderr_line!("handy: installing the interrupt handler: {error}");
        return ExitCode::FAILURE;
    }
    let result = match &cli.command {
        Command::Train(args) => train::run(args),
        Command::Eval(args) => eval::run(args),
        Command::Sample(args) => sample::run(args),
        Command::Fit(args) => fit::run(args),
        Command::Interpolate(args) => interpolate::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            stderr_line!("handy: {error:#}");
            ExitCode::FAILURE
        }
    }
}
