//! Checks the fair curvature metrics (CE, RE, SDM of ch. 5.4 at one location set and scale)
//! against the sanity cases of docs/losses.md: a uniform random subsample scores near zero at
//! any ratio, TCP scores worse than FPS and random, the values do not move with the input's
//! density, and how much they move with the kernel radius. The earlier own-density CE and SDM
//! are printed beside them.
//!
//! ```text
//! cargo run --release -p meshgnn-losses --example fair_curvature_metrics -- [MESH.ply ...]
//! ```
//! Shapes: an ellipsoid (semi-axes 1.6, 1, 0.7), the subdivided cube, and every mesh given.
//! Each is sampled with 100k area-weighted points twice (seeds 1 and 4: the spread between two
//! samplings of one density) and with 1M (seed 2); 5k and 1k points are kept by random
//! (seed 3), FPS (first point 0) and TCP (top K̄, k = 16), and 5% of the 1M (50k, the same
//! ratio as 100k → 5k) by random and FPS. One line per case: the metrics at
//! kernel scales 1, 0.5 and 2, the earlier variants, the seconds of one evaluation and of its
//! curvature fields alone.

use meshgnn_geometry::{
    TriMesh, curvature_features, icosphere, read_mesh, sample_surface, subdivided_cube,
    unit_sphere_normalization,
};
use meshgnn_graph::{FpsStart, fast_farthest_point_sampling, top_curvature_sampling};
use meshgnn_losses::metrics::{
    matched_scale_curvature, nearest_value_error, point_cloud_evaluation,
    point_cloud_evaluation_at_scale,
};
use rand::{SeedableRng, rngs::StdRng, seq::index::sample};
use std::time::Instant;

type Cloud = Vec<[f32; 3]>;

fn ellipsoid() -> Result<TriMesh, meshgnn_geometry::Error> {
    let sphere = icosphere(6);
    let stretched = sphere
        .vertices()
        .iter()
        .map(|p| [1.6 * p[0], p[1], 0.7 * p[2]])
        .collect();
    sphere.with_vertices(stretched)
}

fn picked(points: &[[f32; 3]], indices: impl IntoIterator<Item = usize>) -> Cloud {
    indices.into_iter().map(|i| points[i]).collect()
}

/// The earlier CE: each cloud's K̄ on its own 16 nearest, compared at the nearest kept point.
fn own_density_ce(
    original: &[[f32; 3]],
    kept: &[[f32; 3]],
) -> Result<f64, Box<dyn std::error::Error>> {
    let norm = unit_sphere_normalization(original)?;
    let (a, b) = (norm.apply(original), norm.apply(kept));
    let (fa, fb) = (curvature_features(&a, 16)?, curvature_features(&b, 16)?);
    Ok(nearest_value_error(
        &a,
        &fa.mean_curvature,
        &b,
        &fb.mean_curvature,
    )?)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut shapes: Vec<(String, TriMesh)> = vec![
        ("ellipsoid".into(), ellipsoid()?),
        ("cube".into(), subdivided_cube(32)),
    ];
    for path in std::env::args().skip(1) {
        shapes.push((path.clone(), read_mesh(&path)?));
    }
    println!("threads {}", rayon::current_num_threads());
    println!(
        "shape | N (seed) | kept | method | CE s1 | RE s1 | SDM s1 | CE s0.5 | SDM s0.5 | CE s2 | SDM s2 | CE own-density | SDM-nn | eval s | fields s"
    );
    for (name, mesh) in &shapes {
        for (n, seed) in [(100_000usize, 1u64), (100_000, 4), (1_000_000, 2)] {
            let cloud = sample_surface(mesh, n, seed)?.points;
            let k_bar = curvature_features(&cloud, 16)?.mean_curvature;
            let same_ratio = (n > 100_000).then_some(n / 20);
            for m in same_ratio.into_iter().chain([5_000usize, 1_000]) {
                let mut rng = StdRng::seed_from_u64(3);
                let mut random = sample(&mut rng, n, m).into_vec();
                random.sort_unstable();
                let fps = fast_farthest_point_sampling(&cloud, m, FpsStart::Index(0))?;
                let tcp = top_curvature_sampling(&k_bar, m)?;
                let mut methods = vec![
                    ("random", picked(&cloud, random)),
                    ("fps", picked(&cloud, fps.iter().map(|&i| i as usize))),
                ];
                if Some(m) != same_ratio {
                    methods.push(("tcp", picked(&cloud, tcp.iter().map(|&i| i as usize))));
                }
                for (method, kept) in methods {
                    let start = Instant::now();
                    let e = point_cloud_evaluation(&cloud, &kept, 16)?;
                    let seconds = start.elapsed().as_secs_f64();
                    let start = Instant::now();
                    matched_scale_curvature(&cloud, &kept, 16, 1.0)?;
                    let fields = start.elapsed().as_secs_f64();
                    let half = point_cloud_evaluation_at_scale(&cloud, &kept, 16, 0.5)?;
                    let double = point_cloud_evaluation_at_scale(&cloud, &kept, 16, 2.0)?;
                    println!(
                        "{name} | {n} ({seed}) | {m} | {method} | {:.3e} | {:.3e} | {:.3e} | {:.3e} | {:.3e} | {:.3e} | {:.3e} | {:.3e} | {:.3} | {seconds:.2} | {fields:.2}",
                        e.ce,
                        e.re,
                        e.sdm,
                        half.ce,
                        half.sdm,
                        double.ce,
                        double.sdm,
                        own_density_ce(&cloud, &kept)?,
                        e.sdm_nearest,
                    );
                }
            }
        }
    }
    Ok(())
}
