//! Tiny templates and shape sets shared by the tests of the `handy` module.

use meshgnn_geometry::TriMesh;

use crate::handy::spiral::SpiralAutoencoderConfig;

/// A 2-level network (162 → 42 → 12 vertices on `icosphere(2)`).
pub(crate) fn tiny_config(latent_size: usize) -> SpiralAutoencoderConfig {
    SpiralAutoencoderConfig {
        channels: vec![8, 16],
        latent_size,
        factors: vec![4.0; 2],
        spiral_lengths: vec![9; 3],
        dilations: vec![1; 3],
        ..Default::default()
    }
}

/// `count` smooth deformations of `template` (anisotropic scale, a bend and a translation),
/// in "mm".
pub(crate) fn deformed_shapes(template: &TriMesh, count: usize) -> Vec<Vec<[f32; 3]>> {
    (0..count)
        .map(|s| {
            let t = s as f32 / count.max(1) as f32;
            template
                .vertices()
                .iter()
                .map(|p| {
                    [
                        10.0 * (p[0] * (0.8 + 0.4 * t) + t),
                        10.0 * (p[1] + 0.3 * t * p[0] * p[0] + 0.5 * t),
                        10.0 * (p[2] * (1.2 - 0.3 * t) - 0.8 * t),
                    ]
                })
                .collect()
        })
        .collect()
}

/// `count` shapes of full PCA rank: [`deformed_shapes`] plus a small deterministic offset of
/// every vertex that differs from shape to shape.
pub(crate) fn varied_shapes(template: &TriMesh, count: usize) -> Vec<Vec<[f32; 3]>> {
    let mut shapes = deformed_shapes(template, count);
    for (i, shape) in shapes.iter_mut().enumerate() {
        for (v, p) in shape.iter_mut().enumerate() {
            for (c, x) in p.iter_mut().enumerate() {
                *x += 0.01 * ((i * 7 + v * 3 + c * 5) % 11) as f32;
            }
        }
    }
    shapes
}
