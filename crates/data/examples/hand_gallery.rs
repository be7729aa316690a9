//! Renders a contact sheet of random hands: `cargo run -p meshgnn-data --example hand_gallery -- out.png [subdivisions]`.

use meshgnn_data::{HandPose, HandShape, HandTemplate, View, contact_sheet, write_png};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let out = args.next().unwrap_or_else(|| "hands.png".into());
    let levels: u32 = args.next().map(|s| s.parse()).transpose()?.unwrap_or(2);
    let template = HandTemplate::new(levels)?;
    let mut meshes = vec![template.generate(&HandShape::adult(), &HandPose::rest())?];
    for i in 0..7u64 {
        let age = [4.0, 30.0, 60.0, 9.0, 25.0, 45.0, 15.0][i as usize];
        meshes.push(template.generate(&HandShape::random(age, i)?, &HandPose::random(100 + i))?);
    }
    let view = View {
        yaw: 0.0,
        pitch: -35.0,
    };
    write_png(&out, &contact_sheet(&meshes, 4, 256, view)?)?;
    println!("{} vertices, wrote {out}", template.vertex_count());
    Ok(())
}
