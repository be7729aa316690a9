//! Invariants of the synthetic hand set: shared topology, manifold with a single wrist
//! boundary, no self-intersections, determinism, and non-linearity of articulation (PCA).

use meshgnn_data::{
    HandGesture, HandPose, HandSetConfig, HandShape, HandTemplate, relax_until_free,
    self_intersections,
};
use meshgnn_geometry::{TriMesh, boundary_loops, mesh_report};
use meshgnn_losses::metrics::compactness;

fn cfg(level: u32, articulated: bool) -> HandSetConfig {
    HandSetConfig {
        subdivisions: level,
        articulated,
        seed: 11,
        ..Default::default()
    }
}

#[test]
fn samples_share_topology_and_are_manifold_with_one_wrist_loop() {
    let t = HandTemplate::new(2).unwrap();
    for i in 0..6 {
        let s = cfg(2, true).sample(&t, i).unwrap();
        let mesh = TriMesh::new(s.vertices, t.triangles().to_vec()).unwrap();
        let r = mesh_report(&mesh);
        assert!(r.edge_manifold && r.vertex_manifold, "{r:?}");
        assert_eq!(r.components, 1);
        assert_eq!(r.degenerate_faces, 0, "sample {i}");
        let loops = boundary_loops(&mesh);
        assert_eq!(loops.len(), 1, "sample {i}");
        for &v in &loops[0] {
            assert!(
                mesh.vertices()[v as usize][1].abs() < 1e-3,
                "wrist loop off the y = 0 plane"
            );
        }
    }
}

#[test]
fn generated_hands_do_not_self_intersect() {
    let t = HandTemplate::new(1).unwrap();
    let rest = t.generate(&HandShape::adult(), &HandPose::rest()).unwrap();
    assert_eq!(self_intersections(&rest), 0);
    for i in 0..8 {
        let s = cfg(1, true).sample(&t, i).unwrap();
        let mesh = TriMesh::new(s.vertices, t.triangles().to_vec()).unwrap();
        assert_eq!(self_intersections(&mesh), 0, "hand {i} pose {:?}", s.pose);
    }
}

#[test]
fn every_gesture_and_the_range_limits_come_out_free_of_self_intersections() {
    let t = HandTemplate::new(2).unwrap();
    let cfg = cfg(2, true);
    let mut seen = std::collections::HashSet::new();
    for i in 0..40 {
        let s = cfg.sample(&t, i).unwrap();
        seen.insert(s.gesture);
        let mesh = TriMesh::new(s.vertices, t.triangles().to_vec()).unwrap();
        assert_eq!(self_intersections(&mesh), 0, "hand {i} {:?}", s.gesture);
        assert!(s.pose.in_range(), "hand {i}");
    }
    assert_eq!(seen.len(), HandGesture::ALL.len(), "{seen:?}");
    // A shape that intersects itself even at rest is reported, to be drawn again.
    let folded = HandShape::random(1.0, 0).unwrap();
    assert!(self_intersections(&t.generate(&folded, &HandPose::rest()).unwrap()) > 0);
    assert!(
        relax_until_free(&t, &folded, &HandPose::rest())
            .unwrap()
            .is_none()
    );
    // The wrist at its limits, the hand flat or spread.
    let shape = HandShape::random(30.0, 3).unwrap();
    for gesture in [HandGesture::Flat, HandGesture::Spread] {
        for wrist in [[-40.0, -15.0], [50.0, 25.0], [50.0, -15.0], [-40.0, 25.0]] {
            let mut pose = gesture.pose(&shape);
            pose.wrist = wrist.map(f64::to_radians);
            assert!(pose.in_range());
            let mesh = t.generate(&shape, &pose).unwrap();
            assert_eq!(self_intersections(&mesh), 0, "{gesture:?} wrist {wrist:?}");
        }
    }
}

#[test]
fn same_seed_same_arrays_different_seed_differs() {
    let t = HandTemplate::new(1).unwrap();
    let a = cfg(1, true).sample(&t, 3).unwrap();
    let b = cfg(1, true).sample(&t, 3).unwrap();
    assert_eq!(a.vertices, b.vertices);
    let other = HandSetConfig {
        seed: 12,
        ..cfg(1, true)
    };
    assert_ne!(a.vertices, other.sample(&t, 3).unwrap().vertices);
    // Determinism does not depend on the thread count.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let c = pool.install(|| cfg(1, true).sample(&t, 3).unwrap());
    assert_eq!(a.vertices, c.vertices);
}

#[test]
fn articulation_makes_the_shape_space_non_linear() {
    let t = HandTemplate::new(1).unwrap();
    let set = |articulated| -> Vec<Vec<[f32; 3]>> {
        (0..150)
            .map(|i| cfg(1, articulated).sample(&t, i).unwrap().vertices)
            .collect()
    };
    let posed = compactness(&set(true)).unwrap();
    let still = compactness(&set(false)).unwrap();
    let (np, ns) = (posed.components_for(0.95), still.components_for(0.95));
    eprintln!("components for 95 %: posed {np}, pose-free {ns}");
    assert!(np >= 2 * ns, "posed {np} vs pose-free {ns}");
}

#[test]
fn children_split_holds_only_children_and_training_holds_some() {
    let t = HandTemplate::new(1).unwrap();
    let c = HandSetConfig {
        children_fraction: 0.5,
        test_fraction: 0.3,
        ..cfg(1, true)
    };
    let samples: Vec<_> = (0..60).map(|i| c.sample(&t, i).unwrap()).collect();
    let child = |s: &meshgnn_data::HandSample| s.shape.age < meshgnn_data::CHILD_AGE;
    for split in ["children", "test", "train"] {
        assert!(samples.iter().any(|s| s.split == split), "no {split}");
    }
    assert!(samples.iter().any(|s| s.split == "train" && child(s)));
    assert!(samples.iter().any(|s| s.split == "train" && !child(s)));
    for s in samples.iter().filter(|s| s.split != "train") {
        assert_eq!(s.split == "children", child(s));
    }
}
