//! Criterion bench of `read_mesh` (docs/io.md) on the 1.3M-triangle files written by
//! `cargo run --release -p meshgnn-geometry --example write_bench_mesh` into bench-data/:
//! binary PLY, ASCII PLY and OBJ, throughput in bytes of file (criterion prints MiB/s).
//! A missing file is skipped with a note, so the bench never fails for lack of data.
//!
//! Run: `cargo bench --bench io`

use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use meshgnn::geometry::read_mesh;

fn io(c: &mut Criterion) {
    let mut group = c.benchmark_group("read_mesh");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(4));
    for name in ["io_1m.ply", "io_1m_ascii.ply", "io_1m.obj"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("bench-data")
            .join(name);
        let Ok(metadata) = std::fs::metadata(&path) else {
            eprintln!("skipping {name}: run the write_bench_mesh example first");
            continue;
        };
        group.throughput(Throughput::Bytes(metadata.len()));
        group.bench_function(name, |b| b.iter(|| read_mesh(black_box(&path))));
    }
    group.finish();
}

criterion_group!(benches, io);
criterion_main!(benches);
