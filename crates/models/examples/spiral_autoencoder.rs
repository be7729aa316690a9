//! Builds a "Handy++" spiral autoencoder (thesis ch. 3.3.4, Table 3.1) on the procedural hand
//! template, trains it briefly on synthetic hands, and reports reconstruction errors.
//!
//! ```text
//! cargo run --release --example spiral_autoencoder -p meshgnn-models [-- --epochs N --subdivisions S]
//! cargo run --release --example spiral_autoencoder -p meshgnn-models -- --export DIR
//! ```
//! `--export DIR` writes the template tensors (spirals, pooling, unpooling) of the default
//! hand template (`HandTemplate::new(3)`) to `DIR/spiral_template.safetensors` for the PyTorch
//! peer benchmark (`benches/peers/spiral_autoencoder_torch.py`) and exits.

use std::path::PathBuf;

use candle_core::Device;
use meshgnn_data::{HandSetConfig, HandTemplate};
use meshgnn_geometry::TriMesh;
use meshgnn_models::MorphableModel;
use meshgnn_models::spiral::{
    SpiralAutoencoderConfig, SpiralTraining, TemplateTensors, mesh_batch,
};
use meshgnn_models::training::{self, TrainingConfig};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let device = Device::Cpu;
    let config = SpiralAutoencoderConfig::default();

    if let Some(dir) = value("--export") {
        let hand = HandTemplate::new(3)?;
        let template = TriMesh::new(hand.rest_vertices(), hand.triangles().to_vec())?;
        let tensors = TemplateTensors::new(&template, &config.hierarchy_options(), &device)?;
        let named = tensors.to_named_tensors("")?;
        let path = PathBuf::from(dir).join("spiral_template.safetensors");
        candle_core::safetensors::save(&named, &path)?;
        println!(
            "vertex counts {:?} → {}",
            tensors.vertex_counts(),
            path.display()
        );
        return Ok(());
    }

    let epochs: usize = value("--epochs").map_or(Ok(20), |v| v.parse())?;
    let subdivisions: u32 = value("--subdivisions").map_or(Ok(2), |v| v.parse())?;
    let hand = HandTemplate::new(subdivisions)?;
    let template = TriMesh::new(hand.rest_vertices(), hand.triangles().to_vec())?;
    let set = HandSetConfig {
        count: 96,
        subdivisions,
        children_fraction: 0.0,
        test_fraction: 0.2,
        ..Default::default()
    };
    let (mut train, mut test) = (Vec::new(), Vec::new());
    for i in 0..set.count {
        let sample = set.sample(&hand, i)?;
        if sample.split == "train" {
            train.push(sample.vertices);
        } else {
            test.push(sample.vertices);
        }
    }
    println!(
        "template: {} vertices, {} faces; {} training and {} test hands",
        template.vertex_count(),
        template.face_count(),
        train.len(),
        test.len()
    );
    let train_config = TrainingConfig {
        epochs,
        ..Default::default()
    };
    let mut task = SpiralTraining::new(&template, &config, &train, &test, 0, &device)?;
    let trained = training::train(&mut task, &train_config, &mut |p| {
        if p.epoch_end {
            println!(
                "epoch {:3}/{}  train L1 {:.4}  train {:.3} mm  test {:.3} mm",
                p.epoch + 1,
                p.epochs,
                p.loss,
                p.figure.unwrap_or(f64::NAN),
                p.validation.unwrap_or(f64::NAN)
            );
        }
    })?;
    let model = task.into_model();
    println!(
        "levels {:?}, trained in {:.1} s",
        model.template_tensors().vertex_counts(),
        trained.seconds
    );

    let x = mesh_batch(&test, &device)?;
    let z = model.encode(&x)?;
    let y = model.decode(&z)?;
    let per_vertex = (y - &x)?.sqr()?.sum(2)?.sqrt()?;
    let mean = per_vertex.mean_all()?.to_scalar::<f32>()?;
    let max = per_vertex.flatten_all()?.max(0)?.to_scalar::<f32>()?;
    println!(
        "test reconstruction through a {}-d latent: mean {mean:.3} mm, max {max:.3} mm",
        model.latent_size()
    );
    Ok(())
}
