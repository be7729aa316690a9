//! The learnable point-cloud simplifier (thesis ch. 5) with the bundled weights: simplify a
//! zero-shot shape (the `fandisk` test family, never seen in training) to 5%, print the time
//! split (k-NN / projector / selector / AttRef) and the ch. 5.4 metrics next to plain FPS.
//!
//! ```text
//! cargo run --release -p meshgnn-models --example point_simplifier -- [--points N] [--ratio R]
//!     [--compare-selector] [--weights FILE]
//! ```
//! `--compare-selector` also measures the cost of the cell-partitioned latent FPS against exact
//! latent FPS on a 20k-point cloud.

use std::time::Instant;

use meshgnn_data::{ShapeFamily, shape_mesh};
use meshgnn_geometry::sample_surface;
use meshgnn_graph::{FpsStart, fast_farthest_point_sampling};
use meshgnn_losses::metrics::{PointCloudEvaluation, point_cloud_evaluation};
use meshgnn_models::point_simplifier::{
    LatentSamplingOptions, PointSimplifier, Simplification, SimplifyOptions,
};

type AnyResult<T> = std::result::Result<T, Box<dyn std::error::Error>>;

fn arg<T: std::str::FromStr>(args: &[String], name: &str, default: T) -> T {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn print_metrics(name: &str, e: &PointCloudEvaluation) {
    println!(
        "  {name:<22} CD {:.3e}  NC {:.4}  CE {:.3e}  RE {:.3e}  SDM {:.3e}  SDM-nn {:.4}",
        e.cd, e.nc, e.ce, e.re, e.sdm, e.sdm_nearest
    );
}

fn print_split(s: &Simplification) {
    let t = s.timings;
    let total = s.total.as_secs_f64();
    let pct = |d: std::time::Duration| 100.0 * d.as_secs_f64() / total;
    println!(
        "  total {:.3} s: k-NN {:.3} s ({:.0}%), projector {:.3} s ({:.0}%), selector {:.3} s ({:.0}%), AttRef {:.3} s ({:.0}%)",
        total,
        t.knn.as_secs_f64(),
        pct(t.knn),
        t.projector.as_secs_f64(),
        pct(t.projector),
        t.selector.as_secs_f64(),
        pct(t.selector),
        t.refinement.as_secs_f64(),
        pct(t.refinement),
    );
}

fn main() -> AnyResult<()> {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = arg(&args, "--points", 100_000);
    let ratio: f64 = arg(&args, "--ratio", 0.05);
    let model = match args.iter().position(|a| a == "--weights") {
        Some(i) => PointSimplifier::load(args.get(i + 1).ok_or("--weights needs a file")?)?,
        None => meshgnn_models::pretrained::load("point_simplifier")?,
    };
    let mesh = shape_mesh(ShapeFamily::Fandisk, 7, 96)?;
    let cloud = sample_surface(&mesh, n, 1)?.points;
    let target = ((ratio * n as f64).round() as usize).clamp(1, n);
    println!(
        "fandisk (test family), {n} points → {target} ({:.1}%)",
        100.0 * ratio
    );

    let options = SimplifyOptions::default();
    let _warm = model.simplify(&cloud, None, None, target, &options)?;
    let out = model.simplify(&cloud, None, None, target, &options)?;
    println!("neural simplifier (bundled weights):");
    print_split(&out);
    let t = Instant::now();
    let fps = fast_farthest_point_sampling(&cloud, target, FpsStart::Seeded(0))?;
    println!("  xyz FPS baseline: {:.3} s", t.elapsed().as_secs_f64());
    let fps_points: Vec<[f32; 3]> = fps.iter().map(|&i| cloud[i as usize]).collect();
    let kept: Vec<[f32; 3]> = out.indices.iter().map(|&i| cloud[i as usize]).collect();
    println!("metrics against the input (unit-sphere normalised):");
    print_metrics(
        "neural (refined)",
        &point_cloud_evaluation(&cloud, &out.points, 16)?,
    );
    print_metrics(
        "neural (selection)",
        &point_cloud_evaluation(&cloud, &kept, 16)?,
    );
    print_metrics("xyz FPS", &point_cloud_evaluation(&cloud, &fps_points, 16)?);

    if args.iter().any(|a| a == "--compare-selector") {
        let small = sample_surface(&mesh, 20_000, 2)?.points;
        let m = 1000;
        println!("selector approximation on 20000 points → {m}:");
        for (name, cell) in [
            ("exact latent FPS", 20_000),
            ("cells of 4096", 4096),
            ("cells of 2048 (default)", 2048),
            ("cells of 1024", 1024),
        ] {
            let o = SimplifyOptions {
                selection: LatentSamplingOptions { cell_size: cell },
                seed: 0,
            };
            let s = model.simplify(&small, None, None, m, &o)?;
            let e = point_cloud_evaluation(&small, &s.points, 16)?;
            print_metrics(name, &e);
            println!("    selector {:.3} s", s.timings.selector.as_secs_f64());
        }
    }
    Ok(())
}
