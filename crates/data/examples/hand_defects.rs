//! Prints where a hand self-intersects: `cargo run -p meshgnn-data --example hand_defects -- [level] [seed]`.

use meshgnn_data::{HandPose, HandSetConfig, HandShape, HandTemplate, self_intersecting_pairs};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let level: u32 = args.next().map(|s| s.parse()).transpose()?.unwrap_or(1);
    let template = HandTemplate::new(level)?;
    let cfg = HandSetConfig {
        subdivisions: level,
        seed: 11,
        ..Default::default()
    };
    let mut meshes = vec![(
        "rest".to_string(),
        template.generate(&HandShape::adult(), &HandPose::rest())?,
    )];
    for i in 0..8 {
        let s = cfg.sample(&template, i)?;
        meshes.push((
            format!("sample {i}"),
            meshgnn_geometry::TriMesh::new(s.vertices, template.triangles().to_vec())?,
        ));
    }
    for (name, mesh) in &meshes {
        let pairs = self_intersecting_pairs(mesh);
        let centroid = |f: u32| {
            let t = mesh.triangle_positions(f as usize);
            [0, 1, 2].map(|k| ((t[0][k] + t[1][k] + t[2][k]) / 3.0).round())
        };
        let shown: Vec<_> = pairs
            .iter()
            .take(6)
            .map(|p| (centroid(p[0]), centroid(p[1])))
            .collect();
        println!("{name}: {} pairs {:?}", pairs.len(), shown);
    }
    Ok(())
}
