//! k-NN graphs of 1M surface points with k = 7 (projector, thesis eq. 5.4) and k = 15
//! (AttRef eq. 5.5, edge predictor ch. 6.3); throughput in points per second.
//!
//! `cargo bench --bench knn`

// Benchmark set-up on generated, known-valid inputs: a failure is a bug to surface loudly.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use meshgnn::geometry::{icosphere, sample_surface};
use meshgnn::graph::knn_graph;
use std::time::Duration;

fn knn(c: &mut Criterion) {
    let n = 1_000_000;
    let points = sample_surface(&icosphere(5), n, 3)
        .expect("sphere has area")
        .points;
    let mut group = c.benchmark_group("knn_graph");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3))
        .throughput(Throughput::Elements(n as u64));
    for k in [7usize, 15] {
        group.bench_function(BenchmarkId::new("1M", k), |b| {
            b.iter(|| knn_graph(&points, k).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, knn);
criterion_main!(benches);
