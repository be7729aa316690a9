//! Invariants of the simplification shape set.

use meshgnn_data::{ShapeFamily, self_intersections, shape_mesh};
use meshgnn_geometry::mesh_report;

#[test]
fn every_family_is_closed_manifold_and_in_size_range() {
    for family in ShapeFamily::ALL {
        for seed in 0..2 {
            let m = shape_mesh(family, seed, 64).unwrap();
            let r = mesh_report(&m);
            assert!(
                r.watertight && r.edge_manifold && r.vertex_manifold,
                "{family:?} {seed}: {r:?}"
            );
            assert!(
                r.faces >= 10_000 && r.faces <= 200_000,
                "{family:?}: {} faces",
                r.faces
            );
            assert_eq!(self_intersections(&m), 0, "{family:?} {seed}");
        }
    }
}

#[test]
fn splits_are_family_disjoint_and_generation_deterministic() {
    let train: Vec<_> = ShapeFamily::ALL
        .iter()
        .filter(|f| f.split() == "train")
        .collect();
    let test: Vec<_> = ShapeFamily::ALL
        .iter()
        .filter(|f| f.split() == "test")
        .collect();
    assert_eq!((train.len(), test.len()), (3, 2));
    assert!(train.iter().all(|f| !test.contains(f)));
    let a = shape_mesh(ShapeFamily::CreaturesA, 9, 40).unwrap();
    assert_eq!(a, shape_mesh(ShapeFamily::CreaturesA, 9, 40).unwrap());
    assert_ne!(a, shape_mesh(ShapeFamily::CreaturesA, 10, 40).unwrap());
}
