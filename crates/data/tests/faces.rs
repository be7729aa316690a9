//! Invariants of the synthetic face set.

use meshgnn_data::{
    Actions, Expression, ExpressionStyle, FaceIdentity, FaceSetConfig, FaceTemplate, apply_actions,
    apply_styled_actions, self_intersections,
};
use meshgnn_geometry::{TriMesh, boundary_loops, mesh_report};

#[test]
fn template_is_manifold_with_rim_and_mouth_loops() {
    let t = FaceTemplate::default();
    assert!((4500..=5500).contains(&t.vertex_count()));
    let mesh = TriMesh::new(t.neutral(&FaceIdentity::mean()), t.triangles().to_vec()).unwrap();
    let r = mesh_report(&mesh);
    assert!(r.edge_manifold && r.vertex_manifold);
    let mut loops = boundary_loops(&mesh);
    loops.sort_by_key(Vec::len);
    assert_eq!(loops.len(), 2, "outer rim + mouth");
    // The mouth loop is the short one, around the mouth line in front.
    for &v in &loops[0] {
        assert!(mesh.vertices()[v as usize][2] > 40.0);
    }
}

#[test]
fn expressions_at_full_intensity_do_not_self_intersect() {
    let t = FaceTemplate::default();
    for seed in 0..2 {
        let id = FaceIdentity::random(seed);
        let n = t.neutral(&id);
        assert_eq!(
            self_intersections(&TriMesh::new(n.clone(), t.triangles().to_vec()).unwrap()),
            0
        );
        for e in Expression::ALL {
            let v = apply_actions(&t, &n, &e.actions().scaled(1.15));
            let mesh = TriMesh::new(v, t.triangles().to_vec()).unwrap();
            assert_eq!(self_intersections(&mesh), 0, "{e:?} subject {seed}");
        }
    }
}

#[test]
fn subjects_are_deterministic_and_split_disjointly() {
    let cfg = FaceSetConfig {
        subjects: 20,
        frame_step: 10,
        seed: 5,
    };
    let t = FaceTemplate::new(36, 34).unwrap();
    let a = cfg.subject(&t, 4).unwrap();
    assert_eq!(a, cfg.subject(&t, 4).unwrap());
    assert_ne!(
        a.neutral,
        FaceSetConfig { seed: 6, ..cfg }
            .subject(&t, 4)
            .unwrap()
            .neutral
    );
    let splits: Vec<&str> = (0..20).map(|i| cfg.subject(&t, i).unwrap().split).collect();
    assert_eq!(splits.iter().filter(|s| **s == "test").count(), 3);
    for s in &a.sequences {
        assert!((60..=100).contains(&s.timing.frames));
        assert!(s.motion.iter().all(|m| (0.0..=1.0).contains(m)));
    }
}

#[test]
fn every_style_performs_without_self_intersections() {
    // Random subjects' styles and a style at every bound (strongest gains, most lopsided,
    // widest regions, deepest and densest wrinkles), at the largest apex a subject can reach
    // (extremeness 1 × overall scale 1.15).
    let t = FaceTemplate::default();
    let cfg = FaceSetConfig::default();
    let extreme = ExpressionStyle {
        gains: Actions::uniform(1.7),
        asymmetry: 0.3,
        spread: 1.25,
        corner_shift: [0.04, -0.04],
        jaw_band: 1.5,
        jaw_glide: 1.5,
        wrinkle_depth: 1.5,
        wrinkle_spacing: 0.85,
        ..Default::default()
    };
    let styles = [cfg.style(0), cfg.style(1), cfg.style(2), extreme];
    for (i, style) in styles.iter().enumerate() {
        let n = t.neutral(&FaceIdentity::random(i as u64));
        for e in Expression::ALL {
            let a = style.actions_at(&e.actions().scaled(1.15), 1.0);
            let v = apply_styled_actions(&t, &n, &a, style);
            let mesh = TriMesh::new(v, t.triangles().to_vec()).unwrap();
            assert_eq!(self_intersections(&mesh), 0, "{e:?}, style {i}");
        }
    }
}
