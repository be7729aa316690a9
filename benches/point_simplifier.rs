//! The learnable point-cloud simplifier (thesis ch. 5) with the bundled weights: 100k surface
//! points to 5% (k-NN + projector + latent FPS + AttRef), against xyz FPS to the same count.
//! The 1M-point time split is printed by `crates/models/examples/point_simplifier.rs`.
//!
//! `cargo bench --bench point_simplifier`

// Benchmark set-up on generated, known-valid inputs: a failure is a bug to surface loudly.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use meshgnn::geometry::{sample_surface, subdivided_cube};
use meshgnn::graph::{FpsStart, fast_farthest_point_sampling};
use meshgnn_models::point_simplifier::{PointSimplifier, SimplifyOptions};
use std::time::Duration;

fn point_simplifier(c: &mut Criterion) {
    let n = 100_000;
    let target = n / 20;
    let points = sample_surface(&subdivided_cube(16), n, 3)
        .expect("cube has area")
        .points;
    let model = meshgnn_models::pretrained::load::<PointSimplifier>("point_simplifier")
        .expect("bundled weights load");
    let mut group = c.benchmark_group("point_simplifier");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(4))
        .throughput(Throughput::Elements(n as u64));
    group.bench_function("neural_100k_to_5pct", |b| {
        b.iter(|| {
            model
                .simplify(&points, None, None, target, &SimplifyOptions::default())
                .unwrap()
        })
    });
    group.bench_function("xyz_fps_100k_to_5pct", |b| {
        b.iter(|| fast_farthest_point_sampling(&points, target, FpsStart::Index(0)).unwrap())
    });
    group.finish();
}

criterion_group!(benches, point_simplifier);
criterion_main!(benches);
