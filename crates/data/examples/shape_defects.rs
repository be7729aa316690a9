//! Prints self-intersecting pairs of a generated shape: `cargo run -p meshgnn-data --example shape_defects`.

use meshgnn_data::{ShapeFamily, self_intersecting_pairs, shape_mesh};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    for family in ShapeFamily::ALL {
        let mesh = shape_mesh(family, 0, 32)?;
        let pairs = self_intersecting_pairs(&mesh);
        println!(
            "{family:?}: {} faces, {} pairs",
            mesh.face_count(),
            pairs.len()
        );
        for p in pairs.iter().take(2) {
            for f in p {
                println!(
                    "  {f}: {:?} {:?}",
                    mesh.triangles()[*f as usize],
                    mesh.triangle_positions(*f as usize)
                );
            }
        }
    }
    Ok(())
}
