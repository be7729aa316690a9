//! Symmetric Chamfer distance (thesis eq. 5.6) on 100k vs 100k and 1M vs 1M random points.
//! Peers: `benches/peers/chamfer_peers.py` (scipy cKDTree, all cores) on the same points.

use criterion::{Criterion, criterion_group, criterion_main};
use meshgnn::losses::metrics::chamfer_distance;
use rand::{Rng, SeedableRng, rngs::StdRng};
use std::hint::black_box;
use std::time::Duration;

fn random_points(n: usize, seed: u64) -> Vec<[f32; 3]> {
    let mut rng = StdRng::seed_from_u64(seed);
    (0..n)
        .map(|_| [rng.random(), rng.random(), rng.random()])
        .collect()
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("chamfer");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    for n in [100_000usize, 1_000_000] {
        let a = random_points(n, 1);
        let b = random_points(n, 2);
        group.bench_function(format!("symmetric_{n}_vs_{n}"), |bench| {
            bench.iter(|| chamfer_distance(black_box(&a), black_box(&b)))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
