//! The simplification methods `pcsimplify` offers and the one entry point that runs any of
//! them: the thesis' baselines of ch. 5.5 (FPS, random, TCP, QEM) and, when the model crate
//! provides it, the learned simplifier of ch. 5.3.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use meshgnn_geometry::{TriMesh, curvature_features};
use meshgnn_graph::{
    FpsStart, fast_farthest_point_sampling, top_curvature_sampling, uniform_sampling,
    vertex_adjacency,
};
use meshgnn_losses::metrics::EVALUATION_CURVATURE_NEIGHBOURS;
use meshgnn_models::point_simplifier::{PointSimplifier, SimplifyOptions};

use crate::input::Input;
use meshgnn_graph::qem_vertices;

/// A point-selection method.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Method {
    /// The learned simplifier (ch. 5.3): projector, latent FPS, AttRef; mesh adjacency for
    /// mesh inputs, else a k = 7 k-NN.
    Neural,
    /// Farthest point sampling (exact, kd-tree pruned), first point drawn with the seed.
    Fps,
    /// Uniform random sampling without replacement, seeded.
    Random,
    /// Top-curvature points (TCP): the highest mean curvature K̄ (eq. 5.3, k = 16).
    Tcp,
    /// QEM edge collapse keeping original positions (mesh inputs only).
    Qem,
}

impl Method {
    /// The method `simplify` uses without `--method`.
    pub const DEFAULT: Method = Method::Neural;

    /// The methods `bench` compares without `--methods` (Table 5.1's rows we implement).
    pub const BENCH_DEFAULT: [Method; 4] =
        [Method::Neural, Method::Fps, Method::Random, Method::Tcp];

    /// The name used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        match self {
            Self::Neural => "neural",
            Self::Fps => "fps",
            Self::Random => "random",
            Self::Tcp => "tcp",
            Self::Qem => "qem",
        }
    }
}

/// Points kept by a method and where its time went.
#[derive(Debug, Clone)]
pub struct Selection {
    /// Distinct indices into the input points, `#kept`.
    pub indices: Vec<u32>,
    /// `(stage, seconds)` in execution order; one entry for single-stage methods.
    pub timings: Vec<(&'static str, f64)>,
    /// Positions of the kept points when the method moves them (the neural AttRef
    /// refinement, eq. 5.5), `#kept×3`; else the input points at `indices`.
    pub points: Option<Vec<[f32; 3]>>,
    /// The mesh the method built over the kept points (QEM's decimated mesh, vertex `o` at
    /// input point `indices[o]`), when it builds one.
    pub mesh: Option<TriMesh>,
}

impl Selection {
    /// Total seconds over all stages.
    pub fn seconds(&self) -> f64 {
        self.timings.iter().map(|t| t.1).sum()
    }
}

impl Selection {
    /// The kept positions: the method's own (refined) or the input's at `indices`.
    pub fn kept_points(&self, input: &Input) -> Vec<[f32; 3]> {
        match &self.points {
            Some(points) => points.clone(),
            None => self
                .indices
                .iter()
                .filter_map(|&i| input.points.get(i as usize).copied())
                .collect(),
        }
    }
}

/// The learned simplifier: `--weights FILE` or the bundled default weights.
pub fn load_model(weights: Option<&Path>) -> Result<PointSimplifier> {
    match weights {
        Some(path) => PointSimplifier::load(path)
            .with_context(|| format!("loading the simplifier weights {}", path.display())),
        None => PointSimplifier::pretrained().context(
            "loading the bundled simplifier weights (pass --weights FILE, or choose another --method)",
        ),
    }
}

/// `round(ratio × n)` or `points`, checked to be in `1..=n`.
pub fn target_count(n: usize, ratio: Option<f64>, points: Option<usize>) -> Result<usize> {
    let count = match (ratio, points) {
        (Some(r), None) => {
            if !(r.is_finite() && r > 0.0 && r <= 1.0) {
                bail!("--ratio must be in (0, 1], got {r}");
            }
            (r * n as f64).round() as usize
        }
        (None, Some(p)) => p,
        _ => bail!("give exactly one of --ratio and --points"),
    };
    if count == 0 {
        bail!("the target keeps 0 of {n} points: raise --ratio or --points");
    }
    if count > n {
        bail!("cannot keep {count} points: the input has only {n}");
    }
    Ok(count)
}

/// Runs `method` on `input` to keep exactly `count` points; `seed` drives every random choice;
/// `model` is the learned simplifier (needed for [`Method::Neural`] only).
pub fn select(
    method: Method,
    input: &Input,
    count: usize,
    seed: u64,
    model: Option<&PointSimplifier>,
) -> Result<Selection> {
    let n = input.points.len();
    if count == 0 || count > n {
        bail!("cannot keep {count} of {n} points");
    }
    let start = Instant::now();
    let mut mesh = None;
    let indices = match method {
        Method::Neural => {
            let Some(model) = model else {
                bail!("the neural method needs the simplifier weights");
            };
            return select_neural(model, input, count, seed);
        }
        Method::Fps => fast_farthest_point_sampling(&input.points, count, FpsStart::Seeded(seed))?,
        Method::Random => uniform_sampling(n, count, seed)?,
        Method::Tcp => {
            if n <= 2 {
                bail!("TCP needs at least 3 points for curvature, got {n}");
            }
            let k = EVALUATION_CURVATURE_NEIGHBOURS.min(n - 1);
            let features = curvature_features(&input.points, k).context("curvature for TCP")?;
            top_curvature_sampling(&features.mean_curvature, count)?
        }
        Method::Qem => {
            let Some(source) = &input.mesh else {
                bail!(
                    "--method qem needs a mesh input (a file with faces); this is a point cloud: use fps, random or tcp"
                );
            };
            let qem = qem_vertices(source, count)?;
            mesh = Some(qem.mesh);
            qem.indices
        }
    };
    Ok(Selection {
        indices,
        timings: vec![(method.name(), start.elapsed().as_secs_f64())],
        points: None,
        mesh,
    })
}

/// Ch. 5.3 inference: mesh adjacency (mesh inputs) or k-NN, projector, latent FPS, AttRef.
fn select_neural(
    model: &PointSimplifier,
    input: &Input,
    count: usize,
    seed: u64,
) -> Result<Selection> {
    let start = Instant::now();
    let adjacency = match &input.mesh {
        Some(mesh) => Some(vertex_adjacency(mesh).context("mesh adjacency")?),
        None => None,
    };
    let adjacency_seconds = start.elapsed().as_secs_f64();
    let out = model
        .simplify(
            &input.points,
            input.normals.as_deref(),
            adjacency.as_ref(),
            count,
            &SimplifyOptions {
                seed,
                ..Default::default()
            },
        )
        .context("neural simplification")?;
    let t = out.timings;
    Ok(Selection {
        indices: out.indices,
        timings: vec![
            ("knn", adjacency_seconds + t.knn.as_secs_f64()),
            ("projector", t.projector.as_secs_f64()),
            ("selector", t.selector.as_secs_f64()),
            ("attref", t.refinement.as_secs_f64()),
        ],
        points: Some(out.points),
        mesh: None,
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use meshgnn_geometry::{PointCloud, icosphere};

    /// An untrained simplifier (random weights): exercises the neural path without the
    /// bundled weights.
    fn random_model() -> PointSimplifier {
        let map = candle_nn::VarMap::new();
        let vb = candle_nn::VarBuilder::from_varmap(
            &map,
            candle_core::DType::F32,
            &candle_core::Device::Cpu,
        );
        PointSimplifier::new(vb, &Default::default()).unwrap()
    }

    fn distinct(indices: &[u32]) -> usize {
        let mut s = indices.to_vec();
        s.sort_unstable();
        s.dedup();
        s.len()
    }

    #[test]
    fn every_method_returns_the_requested_count_of_distinct_indices() {
        let sphere = Input::from_mesh(icosphere(3)); // 642 vertices
        let cloud = Input::from_cloud(PointCloud::new(sphere.points.clone()).unwrap());
        let model = random_model();
        for count in [1, 64, 642] {
            for input in [&sphere, &cloud] {
                let s = select(Method::Neural, input, count, 7, Some(&model)).unwrap();
                assert_eq!(s.indices.len(), count);
                assert_eq!(distinct(&s.indices), count);
                assert_eq!(s.kept_points(input).len(), count);
                let stages: Vec<&str> = s.timings.iter().map(|t| t.0).collect();
                assert_eq!(stages, ["knn", "projector", "selector", "attref"]);
            }
        }
        assert!(select(Method::Neural, &sphere, 10, 0, None).is_err());
        for method in [Method::Fps, Method::Random, Method::Tcp, Method::Qem] {
            let smallest = if method == Method::Qem { 4 } else { 1 }; // a closed mesh has ≥ 4
            for count in [smallest, 32, 64, 321, 642] {
                let s = select(method, &sphere, count, 7, None).unwrap();
                assert_eq!(s.indices.len(), count, "{method:?} {count}");
                assert_eq!(distinct(&s.indices), count, "{method:?} {count}");
                assert!(s.indices.iter().all(|&i| (i as usize) < 642));
            }
        }
    }

    #[test]
    fn qem_keeps_original_positions_matching_its_mesh() {
        let sphere = Input::from_mesh(icosphere(3));
        let s = select(Method::Qem, &sphere, 100, 0, None).unwrap();
        let mesh = s.mesh.unwrap();
        assert_eq!(mesh.vertex_count(), 100);
        for (o, &i) in s.indices.iter().enumerate() {
            assert_eq!(mesh.vertices()[o], sphere.points[i as usize]);
        }
        // A closed genus-0 input stays closed: F = 2V − 4.
        assert_eq!(mesh.face_count(), 196);
    }

    #[test]
    fn tcp_keeps_points_on_the_sharp_edges_of_a_cube() {
        // Curvature is zero on the faces' interiors and high along the 12 edges; K̄ (eq. 5.3)
        // smooths it over about one grid step (0.1), so every pick lies within a step of an
        // edge (such points are 13 % of the cube's; random picks would miss).
        let cube = meshgnn_geometry::subdivided_cube(20);
        let input = Input::from_mesh(cube);
        let s = select(Method::Tcp, &input, 24, 0, None).unwrap();
        for &i in &s.indices {
            let p = input.points[i as usize];
            let near_faces = p.iter().filter(|x| x.abs() > 0.9 - 1e-5).count();
            assert!(
                near_faces >= 2,
                "point {i} at {p:?} is not next to a cube edge"
            );
        }
    }

    #[test]
    fn qem_is_refused_on_a_cloud() {
        let cloud = Input::from_cloud(PointCloud::new(icosphere(2).vertices().to_vec()).unwrap());
        let err = select(Method::Qem, &cloud, 10, 0, None).unwrap_err();
        assert!(format!("{err:#}").contains("needs a mesh"), "{err:#}");
    }

    #[test]
    fn same_seed_same_selection() {
        let sphere = Input::from_mesh(icosphere(3));
        for method in [Method::Fps, Method::Random] {
            let a = select(method, &sphere, 50, 3, None).unwrap().indices;
            assert_eq!(a, select(method, &sphere, 50, 3, None).unwrap().indices);
            assert_ne!(a, select(method, &sphere, 50, 4, None).unwrap().indices);
        }
    }

    #[test]
    fn target_count_rounds_and_checks() {
        assert_eq!(target_count(1000, Some(0.05), None).unwrap(), 50);
        assert_eq!(target_count(10, Some(0.25), None).unwrap(), 3); // 2.5 rounds away from 0
        assert_eq!(target_count(10, None, Some(10)).unwrap(), 10);
        assert!(target_count(10, Some(0.01), None).is_err()); // rounds to 0
        assert!(target_count(10, None, Some(11)).is_err());
        assert!(target_count(10, Some(1.5), None).is_err());
        assert!(target_count(10, None, None).is_err());
    }
}
