//! QEM decimation of the real meshes in `data-fixtures/real/` (a scan, CAD parts with creases,
//! a bordered multi-part model, a model with a non-manifold edge; licences in
//! data-fixtures/README.md) to 10% of their faces: the target is reached, and no topological
//! defect appears that the input did not have. The error against meshoptimizer is measured
//! outside the tests (`benches/peers/qem_real_meshes.py`, docs/results.md).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::PathBuf;

use meshgnn_geometry::{
    TriMesh, boundary_loops, connected_components, is_watertight, non_manifold_edges, read_mesh,
};
use meshgnn_graph::{DecimationOptions, StopReason, Target, decimate};

fn fixture(name: &str) -> TriMesh {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data-fixtures/real")
        .join(name);
    read_mesh(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn decimated(mesh: &TriMesh, target: Target) -> meshgnn_graph::Decimation {
    decimate(
        mesh,
        &DecimationOptions {
            target,
            ..Default::default()
        },
    )
    .unwrap()
}

/// Decimates `name` to 10% of its faces and checks the count and the topology against the
/// input as the decimation sees it (welded: patches sharing positions are joined).
fn decimates_to_a_tenth(name: &str) {
    let file = fixture(name);
    let target = (file.face_count() as f64 * 0.1).round() as usize;
    let out = decimated(&file, Target::Faces(target));
    let mesh = decimated(&file, Target::Ratio(1.0)).mesh;
    assert_eq!(out.stop_reason, StopReason::TargetReached, "{name}");
    let faces = out.mesh.face_count();
    assert!(
        faces <= target && faces + target / 100 + 1 >= target,
        "{name}: {faces} for {target}"
    );
    assert!(
        non_manifold_edges(&out.mesh) <= non_manifold_edges(&mesh),
        "{name}: non-manifold edges appeared"
    );
    if is_watertight(&mesh) {
        assert!(
            is_watertight(&out.mesh),
            "{name}: a closed input was opened"
        );
    }
    assert!(
        boundary_loops(&out.mesh).len() <= boundary_loops(&mesh).len(),
        "{name}: a hole appeared"
    );
    assert_eq!(
        connected_components(&out.mesh).0,
        connected_components(&mesh).0,
        "{name}: a part vanished or split"
    );
}

#[test]
fn scanned_bunny() {
    decimates_to_a_tenth("bunny.obj");
}

#[test]
fn cad_nut_with_creases() {
    decimates_to_a_tenth("nut.ply");
}

#[test]
fn teapot_of_bordered_patches() {
    decimates_to_a_tenth("teapot.obj");
}

#[test]
fn ant_of_fifteen_parts() {
    decimates_to_a_tenth("ant.ply");
}

#[test]
fn airplane_with_a_non_manifold_edge() {
    decimates_to_a_tenth("airplane.ply");
}
