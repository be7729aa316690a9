//! QEM decimation of a 1.3M-triangle bumpy sphere (icosphere(8) with smooth deterministic
//! bumps, the same surface as `crates/graph/examples/qem.rs --make-bumpy 8`) to 10% and 1%:
//! meshgnn's `decimate` against meshoptimizer's `simplify` (target index count, no error
//! limit, LockBorder).
//!
//! `cargo bench --bench qem`
#![allow(clippy::expect_used)]

use std::time::Duration;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use meshgnn::geometry::{TriMesh, icosphere};
use meshgnn::graph::{DecimationOptions, Target, decimate};

fn bumpy_sphere(subdivisions: u32) -> TriMesh {
    let sphere = icosphere(subdivisions);
    let vertices = sphere
        .vertices()
        .iter()
        .map(|p| {
            let [x, y, z] = p.map(f64::from);
            let r = 1.0
                + 0.05 * (5.0 * x).sin() * (7.0 * y).sin() * (3.0 * z).sin()
                + 0.02 * (17.0 * x + 11.0 * y).sin();
            [x * r, y * r, z * r].map(|c| c as f32)
        })
        .collect();
    sphere.with_vertices(vertices).expect("same vertex count")
}

fn qem(c: &mut Criterion) {
    let mesh = bumpy_sphere(8);
    let indices: Vec<u32> = mesh.triangles().iter().flatten().copied().collect();
    let mut group = c.benchmark_group("qem_1.3M");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(8));
    for ratio in [0.1, 0.01] {
        let target = (ratio * mesh.face_count() as f64).round() as usize;
        group.bench_function(BenchmarkId::new("meshgnn", ratio), |b| {
            b.iter(|| {
                decimate(
                    &mesh,
                    &DecimationOptions {
                        target: Target::Faces(target),
                        ..Default::default()
                    },
                )
                .expect("valid mesh")
            })
        });
        group.bench_function(BenchmarkId::new("meshopt", ratio), |b| {
            let adapter =
                meshopt::VertexDataAdapter::new(meshopt::typed_to_bytes(mesh.vertices()), 12, 0)
                    .expect("tightly packed positions");
            b.iter(|| {
                meshopt::simplify(
                    &indices,
                    &adapter,
                    3 * target,
                    1.0,
                    meshopt::SimplifyOptions::LockBorder,
                    None,
                )
            })
        });
    }
    group.finish();
}

criterion_group!(benches, qem);
criterion_main!(benches);
