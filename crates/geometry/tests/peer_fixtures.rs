//! Files written by other tools read with the right counts and bounding boxes.
//!
//! The fixtures in `data-fixtures/peer/` and the expected values below were produced by
//! `data-fixtures/make_peer_fixtures.py` (trimesh 5.2.0, Open3D 0.20.0, numpy 2.4.6): each row
//! is what the script printed for the mesh as the writing tool held it in memory.

// Test code: a panic in a helper is a failed test, as in the test functions.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use meshgnn_geometry::{read_mesh, read_point_cloud};
use std::path::PathBuf;

type Expected = (&'static str, usize, usize, [f64; 3], [f64; 3]);

const MESHES: &[Expected] = &[
    (
        "box_trimesh.obj",
        8,
        12,
        [-1.0, -0.5, -0.25],
        [1.0, 0.5, 0.25],
    ),
    (
        "box_trimesh.off",
        8,
        12,
        [-1.0, -0.5, -0.25],
        [1.0, 0.5, 0.25],
    ),
    (
        "box_trimesh.glb",
        8,
        12,
        [-1.0, -0.5, -0.25],
        [1.0, 0.5, 0.25],
    ),
    (
        "box_trimesh.ply",
        8,
        12,
        [-1.0, -0.5, -0.25],
        [1.0, 0.5, 0.25],
    ),
    (
        "box_trimesh_ascii.ply",
        8,
        12,
        [-1.0, -0.5, -0.25],
        [1.0, 0.5, 0.25],
    ),
    (
        "icosphere_trimesh.obj",
        162,
        320,
        [-1.25, -2.0, -0.5],
        [1.75, 1.0, 2.5],
    ),
    (
        "icosphere_trimesh.off",
        162,
        320,
        [-1.25, -2.0, -0.5],
        [1.75, 1.0, 2.5],
    ),
    (
        "icosphere_trimesh.glb",
        162,
        320,
        [-1.25, -2.0, -0.5],
        [1.75, 1.0, 2.5],
    ),
    (
        "icosphere_trimesh.ply",
        162,
        320,
        [-1.25, -2.0, -0.5],
        [1.75, 1.0, 2.5],
    ),
    (
        "icosphere_trimesh_ascii.ply",
        162,
        320,
        [-1.25, -2.0, -0.5],
        [1.75, 1.0, 2.5],
    ),
    (
        "sphere_open3d.ply",
        266,
        528,
        [0.25, 1.25, 2.25],
        [1.75, 2.75, 3.75],
    ),
    (
        "sphere_open3d_ascii.ply",
        266,
        528,
        [0.25, 1.25, 2.25],
        [1.75, 2.75, 3.75],
    ),
    (
        "sphere_open3d.obj",
        266,
        528,
        [0.25, 1.25, 2.25],
        [1.75, 2.75, 3.75],
    ),
    (
        "sphere_open3d.off",
        266,
        528,
        [0.25, 1.25, 2.25],
        [1.75, 2.75, 3.75],
    ),
    (
        "sphere_open3d.glb",
        266,
        528,
        [0.25, 1.25, 2.25],
        [1.75, 2.75, 3.75],
    ),
];

const CLOUDS: &[Expected] = &[
    (
        "cloud_open3d.ply",
        266,
        0,
        [0.25, 1.25, 2.25],
        [1.75, 2.75, 3.75],
    ),
    (
        "cloud_open3d.xyz",
        266,
        0,
        [0.25, 1.25, 2.25],
        [1.75, 2.75, 3.75],
    ),
];

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data-fixtures/peer")
        .join(name)
}

fn assert_bounds(name: &str, points: &[[f32; 3]], lo: [f64; 3], hi: [f64; 3]) {
    for k in 0..3 {
        let min = points
            .iter()
            .map(|p| f64::from(p[k]))
            .fold(f64::INFINITY, f64::min);
        let max = points
            .iter()
            .map(|p| f64::from(p[k]))
            .fold(f64::NEG_INFINITY, f64::max);
        // The script printed 6 decimals; f32 storage adds < 1e-6 relative error.
        assert!(
            (min - lo[k]).abs() < 2e-6,
            "{name}: min[{k}] {min} != {}",
            lo[k]
        );
        assert!(
            (max - hi[k]).abs() < 2e-6,
            "{name}: max[{k}] {max} != {}",
            hi[k]
        );
    }
}

#[test]
fn peer_meshes_have_the_writers_counts_and_bounds() {
    for &(name, vertices, faces, lo, hi) in MESHES {
        let mesh = read_mesh(fixture(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(mesh.vertex_count(), vertices, "{name} vertices");
        assert_eq!(mesh.face_count(), faces, "{name} faces");
        assert_bounds(name, mesh.vertices(), lo, hi);
        // Every peer mesh is closed: each triangle index is in range and used.
        let mut used = vec![false; vertices];
        mesh.triangles()
            .iter()
            .flatten()
            .for_each(|&v| used[v as usize] = true);
        assert!(used.iter().all(|&u| u), "{name}: unreferenced vertex");
    }
}

#[test]
fn peer_point_clouds_have_the_writers_counts_and_bounds() {
    for &(name, points, _, lo, hi) in CLOUDS.iter().chain(MESHES) {
        let cloud = read_point_cloud(fixture(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(cloud.len(), points, "{name} points");
        assert_bounds(name, cloud.points(), lo, hi);
    }
}

#[test]
fn open3d_normals_are_read_as_unit_vectors() {
    for name in [
        "sphere_open3d.ply",
        "sphere_open3d.obj",
        "sphere_open3d.glb",
    ] {
        let mesh = read_mesh(fixture(name)).unwrap();
        let normals = mesh
            .normals()
            .unwrap_or_else(|| panic!("{name} has normals"));
        for n in normals {
            let length = n.iter().map(|x| x * x).sum::<f32>().sqrt();
            assert!((length - 1.0).abs() < 1e-4, "{name}: |n| = {length}");
        }
    }
}
