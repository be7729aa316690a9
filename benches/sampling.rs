//! Sampling `M` of `N` surface points: exact FPS vs fast (kd-tree) FPS vs weighted sampling
//! without replacement (thesis ch. 6.3: multinomial sampling costs O(N) whatever `M`, FPS
//! O(N·M)). Points: area-weighted samples of a bumpy sphere. Exact FPS runs only where
//! `N·M <= 5e8` (beyond, one iteration takes tens of seconds on 2 cores; see docs/graph.md).
//!
//! `cargo bench --bench sampling`

// Benchmark set-up on generated, known-valid inputs: a failure is a bug to surface loudly.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use meshgnn::geometry::{icosphere, sample_surface};
use meshgnn::graph::{
    FpsStart, farthest_point_sampling, fast_farthest_point_sampling, weighted_sampling,
};
use std::time::Duration;

const EXACT_LIMIT: f64 = 5e8;

fn bumpy_sphere_points(n: usize) -> Vec<[f32; 3]> {
    let sphere = icosphere(5);
    let bumped: Vec<[f32; 3]> = sphere
        .vertices()
        .iter()
        .map(|p| {
            let r = 1.0 + 0.15 * (6.0 * p[0]).sin() * (6.0 * p[1]).sin() * (6.0 * p[2]).sin();
            [p[0] * r, p[1] * r, p[2] * r]
        })
        .collect();
    let mesh = sphere.with_vertices(bumped).expect("same vertex count");
    sample_surface(&mesh, n, 1).expect("sphere has area").points
}

fn sampling(c: &mut Criterion) {
    let mut group = c.benchmark_group("sampling");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    for n in [100_000usize, 1_000_000, 5_000_000] {
        let points = bumpy_sphere_points(n);
        let scores: Vec<f32> = points.iter().map(|p| 1.0 + p[0] * p[0]).collect();
        for percent in [1usize, 5, 20] {
            let m = n * percent / 100;
            let id = format!("{n}/{percent}%");
            group.bench_function(BenchmarkId::new("fast_fps", &id), |b| {
                b.iter(|| fast_farthest_point_sampling(&points, m, FpsStart::Index(0)).unwrap())
            });
            if (n as f64) * (m as f64) <= EXACT_LIMIT {
                group.bench_function(BenchmarkId::new("exact_fps", &id), |b| {
                    b.iter(|| {
                        farthest_point_sampling(points.as_flattened(), 3, m, FpsStart::Index(0))
                            .unwrap()
                    })
                });
            }
            group.bench_function(BenchmarkId::new("weighted", &id), |b| {
                b.iter(|| weighted_sampling(&scores, m, 7).unwrap())
            });
        }
    }
    group.finish();
}

criterion_group!(benches, sampling);
criterion_main!(benches);
