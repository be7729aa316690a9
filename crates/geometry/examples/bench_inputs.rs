//! Writes the inputs of the geometry speed comparison to `bench-data/` (or the folder given
//! as the first argument), so that meshgnn and its peers (Open3D, scipy) time the very same
//! data:
//! - `points_1m.ply`: 1 000 000 points sampled (seed 1) on a bumpy icosphere, binary PLY;
//! - `bumpy_sphere.ply`: icosphere(6) (40 962 vertices) with smooth deterministic bumps;
//! - `cotangent_l.mtx`, `mass_m.mtx`: its cotangent Laplacian and lumped mass matrix
//!   (Matrix Market, general coordinate real, 1-based).
//!
//! Run: `cargo run --release -p meshgnn-geometry --example bench_inputs`

use std::io::Write;
use std::path::{Path, PathBuf};

use meshgnn_geometry::{
    PointCloud, TriMesh, cotangent_laplacian, icosphere, lumped_mass_matrix, sample_surface,
    write_mesh, write_point_cloud,
};

/// icosphere(`subdivisions`) with radius `1 + 0.1 sin 5x cos 4y sin 3z`.
pub fn bumpy_sphere(subdivisions: u32) -> Result<TriMesh, meshgnn_geometry::Error> {
    let sphere = icosphere(subdivisions);
    let moved = sphere
        .vertices()
        .iter()
        .map(|p| {
            let r = 1.0 + 0.1 * (5.0 * p[0]).sin() * (4.0 * p[1]).cos() * (3.0 * p[2]).sin();
            p.map(|x| x * r)
        })
        .collect();
    sphere.with_vertices(moved)
}

fn write_matrix_market(
    path: &Path,
    n: usize,
    entries: impl Iterator<Item = (usize, usize, f64)>,
) -> std::io::Result<()> {
    let entries: Vec<_> = entries.collect();
    let mut out = std::io::BufWriter::new(std::fs::File::create(path)?);
    writeln!(out, "%%MatrixMarket matrix coordinate real general")?;
    writeln!(out, "{n} {n} {}", entries.len())?;
    for (r, c, v) in entries {
        writeln!(out, "{} {} {v:e}", r + 1, c + 1)?;
    }
    out.flush()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "bench-data".into()),
    );
    std::fs::create_dir_all(&dir)?;
    let cloud_mesh = bumpy_sphere(6)?;
    let samples = sample_surface(&cloud_mesh, 1_000_000, 1)?;
    write_point_cloud(dir.join("points_1m.ply"), &PointCloud::new(samples.points)?)?;
    let mesh = bumpy_sphere(6)?;
    write_mesh(dir.join("bumpy_sphere.ply"), &mesh)?;
    let l = cotangent_laplacian(&mesh)?;
    let n = mesh.vertex_count();
    let mut l_entries = Vec::new();
    for col in 0..n {
        let rows = l.symbolic().row_idx_of_col_raw(col);
        for (&row, &value) in rows.iter().zip(l.val_of_col(col)) {
            l_entries.push((row, col, value));
        }
    }
    write_matrix_market(&dir.join("cotangent_l.mtx"), n, l_entries.into_iter())?;
    let mass = lumped_mass_matrix(&mesh);
    write_matrix_market(
        &dir.join("mass_m.mtx"),
        n,
        mass.iter().enumerate().map(|(i, &m)| (i, i, m)),
    )?;
    println!(
        "wrote {} (1e6 points; mesh with {n} vertices, {} faces)",
        dir.display(),
        mesh.face_count()
    );
    Ok(())
}
