//! Criterion benches of the geometric operators of `meshgnn-geometry` (docs/geometry.md):
//! vertex normals on icosphere(8) (1.3M faces), PCA normals and curvature (eq. 5.1-5.2,
//! k = 15) on 1M surface samples, and 150 Laplacian eigenpairs on a 41k-vertex bumpy sphere.
//!
//! Run: `cargo bench --bench geometry`

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use meshgnn::geometry::{
    TriMesh, icosphere, laplacian_eigenvectors, pca_normals_and_curvature, sample_surface,
    vertex_normals,
};

/// icosphere(`subdivisions`) with radius `1 + 0.1 sin 5x cos 4y sin 3z` (as `bench_inputs`).
fn bumpy_sphere(subdivisions: u32) -> TriMesh {
    let sphere = icosphere(subdivisions);
    let moved = sphere
        .vertices()
        .iter()
        .map(|p| {
            let r = 1.0 + 0.1 * (5.0 * p[0]).sin() * (4.0 * p[1]).cos() * (3.0 * p[2]).sin();
            p.map(|x| x * r)
        })
        .collect();
    sphere.with_vertices(moved).unwrap_or_default()
}

fn geometry(c: &mut Criterion) {
    let mut group = c.benchmark_group("geometry");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));

    let sphere = icosphere(8);
    group.throughput(Throughput::Elements(sphere.face_count() as u64));
    group.bench_function("vertex_normals/icosphere8", |b| {
        b.iter(|| vertex_normals(black_box(&sphere)))
    });

    let points = sample_surface(&bumpy_sphere(6), 1_000_000, 1)
        .map(|s| s.points)
        .unwrap_or_default();
    group.throughput(Throughput::Elements(points.len() as u64));
    group.bench_function("pca_normals_and_curvature/k15/1M", |b| {
        b.iter(|| pca_normals_and_curvature(black_box(&points), 15))
    });

    let mesh = bumpy_sphere(6);
    group.throughput(Throughput::Elements(mesh.vertex_count() as u64));
    group.measurement_time(Duration::from_secs(10));
    group.bench_function("laplacian_eigenvectors/k150/41k", |b| {
        b.iter(|| laplacian_eigenvectors(black_box(&mesh), 150))
    });
    group.finish();
}

criterion_group!(benches, geometry);
criterion_main!(benches);
