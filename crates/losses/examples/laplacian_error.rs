//! Times the Laplacian error LE (thesis eq. 6.16, 150 eigenvectors) on a ~20k-vertex mesh
//! against a 5% version of it: a box with sides 2 × 1.6 × 1.2 (anisotropic, so the spectrum
//! has no multiplicities) tessellated at two resolutions.
//!
//! ```text
//! cargo run --release -p meshgnn-losses --example laplacian_error
//! ```

use meshgnn_geometry::{TriMesh, subdivided_cube, unit_sphere_normalization};
use meshgnn_losses::metrics::{LAPLACIAN_EIGENVECTORS, laplacian_error};
use std::time::Instant;

fn box_mesh(n: u32) -> Result<TriMesh, meshgnn_geometry::Error> {
    let cube = subdivided_cube(n);
    let v: Vec<[f32; 3]> = cube
        .vertices()
        .iter()
        .map(|p| [p[0], 0.8 * p[1], 0.6 * p[2]])
        .collect();
    cube.with_vertices(v)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let original = box_mesh(58)?;
    let simplified = box_mesh(13)?;
    let norm = unit_sphere_normalization(original.vertices())?;
    let original = original
        .clone()
        .with_vertices(norm.apply(original.vertices()))?;
    let simplified = simplified
        .clone()
        .with_vertices(norm.apply(simplified.vertices()))?;
    println!(
        "threads {} original {} vertices, simplified {} vertices",
        rayon::current_num_threads(),
        original.vertex_count(),
        simplified.vertex_count()
    );
    let t = Instant::now();
    let le = laplacian_error(&original, &simplified, LAPLACIAN_EIGENVECTORS)?;
    println!("LE {le:.6} in {:.3} s", t.elapsed().as_secs_f64());
    Ok(())
}
