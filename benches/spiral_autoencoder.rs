//! "Handy++" (thesis ch. 3.3.4, Table 3.1) on the default hand template (`HandTemplate::new(3)`,
//! 11 265 vertices, hierarchy factors 4): one training step (forward + L1 + backward + Adam,
//! batch 16), and encode / decode throughput of a batch of 16 hands. The PyTorch peer of the
//! same network is `benches/peers/spiral_autoencoder_torch.py`; figures in
//! docs/spiral_autoencoder.md.
//!
//! `cargo bench --bench spiral_autoencoder`

// Benchmark set-up on generated, known-valid inputs: a failure is a bug to surface loudly.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::time::Duration;

use candle_core::Device;
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use meshgnn::geometry::TriMesh;
use meshgnn::losses::losses::reconstruction_l1;
use meshgnn_data::{HandSetConfig, HandTemplate};
use meshgnn_models::spiral::{
    SpiralAutoencoderConfig, SpiralMorphableModel, VertexNormalization, mesh_batch,
};
use meshgnn_models::{Adam, AdamConfig, MorphableModel, sorted_vars};

const BATCH: usize = 16;

fn spiral_autoencoder(c: &mut Criterion) {
    let hand = HandTemplate::new(3).unwrap();
    let template = TriMesh::new(hand.rest_vertices(), hand.triangles().to_vec()).unwrap();
    let set = HandSetConfig {
        count: BATCH,
        subdivisions: 3,
        ..Default::default()
    };
    let hands: Vec<Vec<[f32; 3]>> = (0..BATCH)
        .map(|i| set.sample(&hand, i).unwrap().vertices)
        .collect();
    let device = Device::Cpu;
    let norm = VertexNormalization::fit(&hands, &device).unwrap();
    let config = SpiralAutoencoderConfig::default();
    let model = SpiralMorphableModel::new(&template, &config, norm, None, 0, &device).unwrap();
    eprintln!("levels {:?}", model.template_tensors().vertex_counts());
    let x = mesh_batch(&hands, &device).unwrap();
    let xn = model.normalization().normalize(&x).unwrap();
    let z = model.encode(&x).unwrap();
    let mut optimizer = Adam::new(sorted_vars(model.vars()), AdamConfig::default()).unwrap();

    let mut group = c.benchmark_group("spiral_autoencoder_11k");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(5))
        .throughput(Throughput::Elements(BATCH as u64));
    group.bench_function("train_step_b16", |b| {
        b.iter(|| {
            let y = model.network().forward(&xn).unwrap();
            let loss = reconstruction_l1(&y, &xn).unwrap();
            optimizer.backward_step(&loss).unwrap();
        })
    });
    group.bench_function("encode_b16", |b| b.iter(|| model.encode(&x).unwrap()));
    group.bench_function("decode_b16", |b| b.iter(|| model.decode(&z).unwrap()));
    group.finish();
}

criterion_group!(benches, spiral_autoencoder);
criterion_main!(benches);
