//! Selection routes under the fair metrics (docs/pcsimplify_model.md, "Selector space"): FPS
//! whose distances are multiplied by a curvature weight `1 + β·K̄/mean K̄` (the best case of a
//! learned bias of FPS distances: the bias is the quantity the curvature metrics read), and FPS
//! followed by three Lloyd steps snapped to the input points (`centroidal_relaxation`, the
//! bundled simplifier's selector), against FPS and random, at the benchmark's ratios; means over
//! the meshes of a folder (their vertices as the cloud).
//!
//! ```text
//! cargo run --release -p meshgnn-models --example selection_routes -- DIR [--betas 0.25,1]
//! ```

use meshgnn_geometry::{curvature_features, read_mesh, squared_distance};
use meshgnn_graph::{
    FpsStart, centroidal_relaxation, fast_farthest_point_sampling, uniform_sampling,
};
use meshgnn_losses::metrics::{EVALUATION_CURVATURE_NEIGHBOURS, point_cloud_evaluation};
use rayon::prelude::*;

type AnyResult<T> = std::result::Result<T, Box<dyn std::error::Error + Send + Sync>>;

/// FPS maximising `weight_i · d_i²` (plain O(N·M) scan; the first point is index 0).
fn weighted_fps(points: &[[f32; 3]], weight: &[f32], count: usize) -> Vec<[f32; 3]> {
    let mut nearest = vec![f32::INFINITY; points.len()];
    let mut kept = Vec::with_capacity(count);
    let mut current = 0;
    for _ in 0..count {
        kept.push(points[current]);
        let centre = points[current];
        let mut best = (f32::NEG_INFINITY, 0);
        for (i, p) in points.iter().enumerate() {
            nearest[i] = nearest[i].min(squared_distance(p, &centre));
            let score = weight[i] * nearest[i];
            if score > best.0 {
                best = (score, i);
            }
        }
        current = best.1;
    }
    kept
}

fn main() -> AnyResult<()> {
    let args: Vec<String> = std::env::args().collect();
    let dir = args
        .get(1)
        .ok_or("usage: selection_routes DIR [--betas B,...]")?;
    let betas: Vec<f32> = match args.iter().position(|a| a == "--betas") {
        Some(i) => args
            .get(i + 1)
            .ok_or("--betas needs values")?
            .split(',')
            .map(str::parse)
            .collect::<Result<_, _>>()?,
        None => vec![0.25, 1.0],
    };
    let mut files: Vec<_> = std::fs::read_dir(dir)?
        .map(|e| e.map(|e| e.path()))
        .collect::<Result<_, _>>()?;
    files.sort();
    let ratios = [0.2, 0.1, 0.05];
    let k = EVALUATION_CURVATURE_NEIGHBOURS;
    // (route, ratio index, [CD, CE, RE, SDM]) per file
    let per_file: Vec<Vec<(String, usize, [f64; 4])>> = files
        .par_iter()
        .map(|path| -> AnyResult<_> {
            let points = read_mesh(path)?.vertices().to_vec();
            let curvature = curvature_features(&points, k)?.mean_curvature;
            let mean =
                curvature.iter().map(|&c| f64::from(c)).sum::<f64>() / curvature.len() as f64;
            let relative: Vec<f32> = curvature
                .iter()
                .map(|&c| (f64::from(c) / mean).min(10.0) as f32)
                .collect();
            let mut rows = Vec::new();
            for (r, ratio) in ratios.iter().enumerate() {
                let count = (ratio * points.len() as f64).round() as usize;
                let at = |indices: Vec<u32>| {
                    indices
                        .iter()
                        .map(|&i| points[i as usize])
                        .collect::<Vec<_>>()
                };
                let fps_indices =
                    fast_farthest_point_sampling(&points, count, FpsStart::Seeded(0))?;
                let mut routes = vec![
                    (
                        "random".to_string(),
                        at(uniform_sampling(points.len(), count, 0)?),
                    ),
                    (
                        "lloyd 3 snapped".to_string(),
                        at(centroidal_relaxation(&points, &fps_indices, 3)?),
                    ),
                ];
                let fps = at(fps_indices);
                for &beta in &betas {
                    let weight: Vec<f32> =
                        relative.iter().map(|&t| (1.0 + beta * t).powi(2)).collect();
                    routes.push((
                        format!("fps bias {beta}"),
                        weighted_fps(&points, &weight, count),
                    ));
                }
                routes.insert(0, ("fps".to_string(), fps));
                for (name, kept) in routes {
                    let e = point_cloud_evaluation(&points, &kept, k)?;
                    rows.push((name, r, [e.cd, e.ce, e.re, e.sdm]));
                }
            }
            Ok(rows)
        })
        .collect::<AnyResult<_>>()?;
    println!(
        "| route | ratio | CD ×10⁻⁴ | CE ×10⁻³ | RE ×10⁻³ | SDM ×10⁻⁴ |\n|---|---:|---:|---:|---:|---:|"
    );
    for (r, ratio) in ratios.iter().enumerate() {
        let names: Vec<&String> = per_file[0]
            .iter()
            .filter(|row| row.1 == r)
            .map(|row| &row.0)
            .collect();
        for name in names {
            let rows: Vec<&[f64; 4]> = per_file
                .iter()
                .flatten()
                .filter(|row| &row.0 == name && row.1 == r)
                .map(|row| &row.2)
                .collect();
            let mean = |j: usize| rows.iter().map(|m| m[j]).sum::<f64>() / rows.len() as f64;
            println!(
                "| {name} | {ratio} | {:.3} | {:.3} | {:.3} | {:.3} |",
                mean(0) * 1e4,
                mean(1) * 1e3,
                mean(2) * 1e3,
                mean(3) * 1e4
            );
        }
    }
    Ok(())
}
