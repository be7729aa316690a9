//! k-NN graphs of 1M surface points with k = 7 (projector, thesis eq. 5.4) and k = 15
//! (AttRef eq. 5.5, edge predictor ch. 6.3); throughput in points per second. Each graph is
//! built twice: with meshgnn's `SpatialIndex` (build + `knn_graph`, what `knn_graph` does) and
//! with kiddo 5's `ImmutableKdTree` (build + one parallel `nearest_n(k + 1)` per point, self
//! dropped), the least work any kiddo-backed index would do before handling duplicates and
//! index tie-breaks. A third group times 200k identical points (the degenerate case kiddo's
//! value-split tree cannot split) with `SpatialIndex` only. Results in `docs/geometry.md`.
//!
//! `cargo bench --bench knn`

// Benchmark set-up on generated, known-valid inputs: a failure is a bug to surface loudly.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::num::NonZero;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use kiddo::SquaredEuclidean;
use kiddo::immutable::float::kdtree::ImmutableKdTree;
use meshgnn::geometry::{SpatialIndex, icosphere, sample_surface};
use rayon::prelude::*;

/// kiddo's k-NN graph: `#P×k` neighbour indices, the point itself dropped (or the farthest
/// when duplicates push it out of the `k + 1` found).
fn kiddo_knn_graph(points: &[[f32; 3]], k: usize) -> Vec<u32> {
    let tree: ImmutableKdTree<f32, u32, 3, 32> = ImmutableKdTree::new_from_slice(points);
    let query = NonZero::new(k + 1).unwrap();
    let mut indices = vec![0u32; points.len() * k];
    indices.par_chunks_mut(k).enumerate().for_each(|(i, row)| {
        let found = tree.nearest_n::<SquaredEuclidean>(&points[i], query);
        let skip = found.iter().position(|n| n.item as usize == i).unwrap_or(k);
        let others = found.iter().enumerate().filter(|&(p, _)| p != skip);
        for (slot, (_, n)) in row.iter_mut().zip(others) {
            *slot = n.item;
        }
    });
    indices
}

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
        group.bench_function(BenchmarkId::new("spatial_index_1M", k), |b| {
            b.iter(|| SpatialIndex::new(&points).unwrap().knn_graph(k).unwrap())
        });
        group.bench_function(BenchmarkId::new("kiddo_1M", k), |b| {
            b.iter(|| kiddo_knn_graph(&points, k))
        });
    }
    group.finish();

    let n = 200_000;
    let identical = vec![[0.25f32, -0.5, 1.0]; n];
    let mut group = c.benchmark_group("knn_graph_identical");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3))
        .throughput(Throughput::Elements(n as u64));
    for k in [7usize, 15] {
        group.bench_function(BenchmarkId::new("spatial_index_200k", k), |b| {
            b.iter(|| SpatialIndex::new(&identical).unwrap().knn_graph(k).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, knn);
criterion_main!(benches);
