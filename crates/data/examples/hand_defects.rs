//! Prints, per random hand, its gesture, the share of the pose kept by contact resolution,
//! where the drawn pose self-intersects and how many pairs the output has left (0 expected):
//! `cargo run -p meshgnn-data --example hand_defects -- [level] [count]`.

use meshgnn_data::{HandSetConfig, HandTemplate, self_intersecting_pairs};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let level: u32 = args.next().map(|s| s.parse()).transpose()?.unwrap_or(2);
    let count: usize = args.next().map(|s| s.parse()).transpose()?.unwrap_or(20);
    let template = HandTemplate::new(level)?;
    let cfg = HandSetConfig {
        subdivisions: level,
        ..Default::default()
    };
    for i in 0..count {
        let s = cfg.sample(&template, i)?;
        let mesh = template.generate(&s.shape, &s.drawn_pose)?;
        let output = meshgnn_geometry::TriMesh::new(s.vertices, template.triangles().to_vec())?;
        let left = self_intersecting_pairs(&output).len();
        let pairs = self_intersecting_pairs(&mesh);
        let centroid = |f: u32| {
            let t = mesh.triangle_positions(f as usize);
            [0, 1, 2].map(|k| ((t[0][k] + t[1][k] + t[2][k]) / 3.0).round())
        };
        let shown: Vec<_> = pairs
            .iter()
            .take(3)
            .map(|p| (centroid(p[0]), centroid(p[1])))
            .collect();
        println!(
            "{} {:?} age {:.0} kept {:.2} {:.2} {:.2} wrist {:?}: drawn {} pairs {:?}, output {left}",
            s.name,
            s.gesture,
            s.shape.age,
            s.kept[0],
            s.kept[1],
            s.kept[2],
            s.pose.wrist.map(|a| a.to_degrees().round()),
            pairs.len(),
            shown
        );
    }
    Ok(())
}
