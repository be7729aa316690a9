//! Times `laplacian_eigenvectors(mesh, k)` on each mesh file given and prints one JSON line
//! per mesh (`mesh`, `vertices`, `seconds`, `values`), for `benches/peers/eigen_peers.py` to
//! set beside scipy's `eigsh` on the same matrices.
//!
//! Run: `cargo run --release -p meshgnn-geometry --example laplacian_eigenpairs -- [--k 150] MESH...`

use std::time::Instant;

use meshgnn_geometry::{laplacian_eigenvectors, read_mesh};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut k = 150;
    if let Some(at) = args.iter().position(|a| a == "--k") {
        k = args.get(at + 1).ok_or("--k needs a value")?.parse()?;
        args.drain(at..at + 2);
    }
    for path in &args {
        let mesh = read_mesh(path)?;
        let start = Instant::now();
        let pairs = laplacian_eigenvectors(&mesh, k)?;
        let seconds = start.elapsed().as_secs_f64();
        let values: Vec<String> = pairs.values.iter().map(|v| format!("{v:e}")).collect();
        println!(
            "{{\"mesh\": \"{path}\", \"vertices\": {}, \"seconds\": {seconds:.4}, \"values\": [{}]}}",
            mesh.vertex_count(),
            values.join(", ")
        );
    }
    Ok(())
}
