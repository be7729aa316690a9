//! Times meshgnn's geometric operators on the inputs of `bench_inputs` (the same data the
//! peers in `benches/peers/geometry_peers.py` time) and prints one `name seconds` line each:
//! - `vertex_normals_icosphere8`: area-weighted vertex normals, 1.3M faces;
//! - `pca_normals_k15_1m`: eq. 5.1-5.2 normals and curvature, k = 15, 1M points (PLY input);
//! - `laplacian_eigenvectors_k150`: 150 eigenpairs of `L x = λ M x` on the 41k-vertex mesh.
//!
//! Each figure is the best of `repeats` runs (first argument, default 3); the second argument
//! is the data folder (default `bench-data`).
//!
//! Run: `cargo run --release -p meshgnn-geometry --example time_ops -- 3 bench-data`

use std::path::PathBuf;
use std::time::Instant;

use meshgnn_geometry::{
    icosphere, laplacian_eigenvectors, pca_normals_and_curvature, read_mesh, read_point_cloud,
    vertex_normals,
};

fn best_of<T>(repeats: usize, mut run: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut last = run();
    for _ in 0..repeats {
        let start = Instant::now();
        last = run();
        best = best.min(start.elapsed().as_secs_f64());
    }
    (best, last)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let repeats: usize = args.next().map(|a| a.parse()).transpose()?.unwrap_or(3);
    let dir = PathBuf::from(args.next().unwrap_or_else(|| "bench-data".into()));
    let threads = rayon::current_num_threads();

    let sphere = icosphere(8);
    let (t, normals) = best_of(repeats, || vertex_normals(&sphere));
    println!(
        "vertex_normals_icosphere8 {t:.6}  # {} faces, {threads} threads",
        sphere.face_count()
    );
    drop(normals);

    let cloud = read_point_cloud(dir.join("points_1m.ply"))?;
    let (t, features) = best_of(repeats, || pca_normals_and_curvature(cloud.points(), 15));
    features?;
    println!(
        "pca_normals_k15_1m {t:.6}  # {:.0} points/s",
        cloud.len() as f64 / t
    );

    let mesh = read_mesh(dir.join("bumpy_sphere.ply"))?;
    let (t, pairs) = best_of(repeats.min(2), || laplacian_eigenvectors(&mesh, 150));
    let pairs = pairs?;
    println!(
        "laplacian_eigenvectors_k150 {t:.6}  # {} vertices, λ_149 = {:.4}",
        mesh.vertex_count(),
        pairs.values.last().copied().unwrap_or(f64::NAN)
    );
    Ok(())
}
