//! Clouds with many coincident points (scans, welded meshes) must work in every k-NN user.
#![allow(clippy::unwrap_used)]

use meshgnn_geometry::{curvature_features, pca_normals_and_curvature};

#[test]
fn heavily_duplicated_clouds_do_not_panic() {
    let mut points = vec![[0.5f32, 0.5, 0.5]; 5_000];
    points.extend((0..200).map(|i| [i as f32 * 0.01, (i % 7) as f32 * 0.1, 0.0]));
    let features = curvature_features(&points, 15).unwrap();
    assert_eq!(features.curvature.len(), points.len());
    let pca = pca_normals_and_curvature(&points, 8).unwrap();
    assert!(pca.normals.iter().all(|n| n.iter().all(|x| x.is_finite())));
}
