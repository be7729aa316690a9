//! Writes the inputs of the geometry speed comparison to `bench-data/` (or the folder given
//! as the first argument), so that meshgnn and its peers (Open3D, scipy) time the very same
//! data:
//! - `points_1m.ply`: 1 000 000 points sampled (seed 1) on a bumpy icosphere, binary PLY;
//! - `bumpy_sphere.ply`: icosphere(6) (40 962 vertices) with smooth deterministic bumps;
//! - `cotangent_l.mtx`, `mass_m.mtx`: its cotangent Laplacian and lumped mass matrix
//!   (Matrix Market, general coordinate real, 1-based);
//! - for every further argument MESH: `STEM_l.mtx` and `STEM_m.mtx`, the same matrices of
//!   that mesh file (the eigen-solver comparison of `benches/peers/eigen_peers.py`).
//!
//! Run: `cargo run --release -p meshgnn-geometry --example bench_inputs [-- DIR [MESH...]]`

use std::io::Write;
use std::path::{Path, PathBuf};

use meshgnn_geometry::{
    PointCloud, TriMesh, cotangent_laplacian, icosphere, lumped_mass_matrix, read_mesh,
    sample_surface, write_mesh, write_point_cloud,
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

/// Writes the cotangent Laplacian of `mesh` to `l_path` and its lumped mass to `m_path`.
fn write_laplacian(mesh: &TriMesh, l_path: &Path, m_path: &Path) -> std::io::Result<()> {
    let l = cotangent_laplacian(mesh).map_err(std::io::Error::other)?;
    let n = mesh.vertex_count();
    let mut l_entries = Vec::new();
    for col in 0..n {
        let rows = l.symbolic().row_idx_of_col_raw(col);
        for (&row, &value) in rows.iter().zip(l.val_of_col(col)) {
            l_entries.push((row, col, value));
        }
    }
    write_matrix_market(l_path, n, l_entries.into_iter())?;
    let mass = lumped_mass_matrix(mesh);
    write_matrix_market(m_path, n, mass.iter().enumerate().map(|(i, &m)| (i, i, m)))
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
    write_laplacian(&mesh, &dir.join("cotangent_l.mtx"), &dir.join("mass_m.mtx"))?;
    println!(
        "wrote {} (1e6 points; mesh with {} vertices, {} faces)",
        dir.display(),
        mesh.vertex_count(),
        mesh.face_count()
    );
    for path in std::env::args().skip(2).map(PathBuf::from) {
        let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("mesh");
        let mesh = read_mesh(&path)?;
        let (l, m) = (format!("{stem}_l.mtx"), format!("{stem}_m.mtx"));
        write_laplacian(&mesh, &dir.join(&l), &dir.join(&m))?;
        println!("wrote {l} and {m} ({} vertices)", mesh.vertex_count());
    }
    Ok(())
}
