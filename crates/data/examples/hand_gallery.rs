//! Renders a contact sheet of hands: every gesture on the mean adult (contact resolved), then
//! random subjects in random poses: `cargo run -p meshgnn-data --example hand_gallery -- out.png [subdivisions] [yaw]`.

use meshgnn_data::{
    HandGesture, HandSetConfig, HandShape, HandTemplate, View, contact_sheet, relax_until_free,
    write_png,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let out = args.next().unwrap_or_else(|| "hands.png".into());
    let levels: u32 = args.next().map(|s| s.parse()).transpose()?.unwrap_or(2);
    let yaw: f64 = args.next().map(|s| s.parse()).transpose()?.unwrap_or(20.0);
    let template = HandTemplate::new(levels)?;
    let adult = HandShape::adult();
    let mut meshes = Vec::new();
    for gesture in HandGesture::ALL {
        let free = relax_until_free(&template, &adult, &gesture.pose(&adult))?
            .ok_or("the mean adult hand intersects itself at rest")?;
        println!(
            "{gesture:?}: kept {:?} of the thumb's, the fingers' and the wrist's angles",
            free.kept
        );
        meshes.push(meshgnn_geometry::TriMesh::new(
            free.vertices,
            template.triangles().to_vec(),
        )?);
    }
    let cfg = HandSetConfig {
        subdivisions: levels,
        ..Default::default()
    };
    for i in 0..9 {
        let s = cfg.sample(&template, i)?;
        println!("{}: {:?}, age {:.0}", s.name, s.gesture, s.shape.age);
        meshes.push(meshgnn_geometry::TriMesh::new(
            s.vertices,
            template.triangles().to_vec(),
        )?);
    }
    let view = View {
        yaw,
        pitch: -35.0,
        wireframe: false,
    };
    write_png(&out, &contact_sheet(&meshes, 4, 256, view)?)?;
    println!("{} vertices, wrote {out}", template.vertex_count());
    Ok(())
}
