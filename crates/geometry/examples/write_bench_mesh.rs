//! Writes the inputs of the I/O speed comparison (docs/io.md): icosphere(8) — 655 362
//! vertices, 1 310 720 triangles — with small deterministic noise (seed 7, so the floats
//! have full precision like a real scan), as `io_1m.ply` (binary little endian),
//! `io_1m_ascii.ply` and `io_1m.obj`, into `bench-data/` or the folder given as argument.
//!
//! Run: `cargo run --release -p meshgnn-geometry --example write_bench_mesh`

use meshgnn_geometry::{PlyEncoding, icosphere, write_mesh, write_ply};
use rand::{Rng, SeedableRng};
use std::path::PathBuf;

fn main() -> Result<(), meshgnn_geometry::Error> {
    let folder = std::env::args_os()
        .nth(1)
        .map_or_else(|| PathBuf::from("bench-data"), PathBuf::from);
    std::fs::create_dir_all(&folder).map_err(|source| meshgnn_geometry::Error::Io {
        path: folder.clone(),
        error: source,
    })?;
    let sphere = icosphere(8);
    let mut rng = rand::rngs::StdRng::seed_from_u64(7);
    let noisy = sphere
        .vertices()
        .iter()
        .map(|p| p.map(|x| x + rng.random_range(-1e-3f32..1e-3)))
        .collect();
    let mesh = sphere.with_vertices(noisy)?;
    write_ply(
        folder.join("io_1m.ply"),
        &mesh,
        PlyEncoding::BinaryLittleEndian,
    )?;
    write_ply(folder.join("io_1m_ascii.ply"), &mesh, PlyEncoding::Ascii)?;
    write_mesh(folder.join("io_1m.obj"), &mesh)?;
    println!(
        "wrote {} vertices, {} triangles to {}",
        mesh.vertex_count(),
        mesh.face_count(),
        folder.display()
    );
    Ok(())
}
