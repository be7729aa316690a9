//! Point-cloud simplification by any method of thesis ch. 5 through one entry point: the
//! learned simplifier of ch. 5.3, the point sampler of ch. 6.3.1 (Table 6.2) and the ch. 5.5
//! baselines (FPS, random, TCP, QEM), each keeping exactly the requested number of points. This crate depends on every crate the
//! methods span (geometry, graph, losses), so the dispatcher lives here, not in an app.

use std::path::Path;
use std::time::Instant;

use meshgnn_geometry::{TriMesh, curvature_features};
use meshgnn_graph::{
    FpsStart, fast_farthest_point_sampling, qem_vertices, top_curvature_sampling, uniform_sampling,
    vertex_adjacency,
};
use meshgnn_losses::metrics::EVALUATION_CURVATURE_NEIGHBOURS;

use crate::mesh_simplifier::NeuralMeshSimplifier;
use crate::point_simplifier::{POINT_SIMPLIFIER_NAME, PointSimplifier, SimplifyOptions};
use crate::{Error, Result, pretrained};

/// A point-selection method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum SelectionMethod {
    /// The learned simplifier (ch. 5.3): projector, latent FPS, AttRef; mesh adjacency for
    /// mesh inputs, else a k = 7 k-NN.
    Neural,
    /// The point sampler of the neural mesh simplifier alone (ch. 6.3.1): learnt inclusion
    /// probabilities, a spatially balanced draw; mesh adjacency for mesh inputs, else a
    /// 6-NN.
    Sampler,
    /// Farthest point sampling (exact, kd-tree pruned), first point drawn with the seed.
    Fps,
    /// Uniform random sampling without replacement, seeded.
    Random,
    /// Top-curvature points (TCP): the highest mean curvature K̄ (eq. 5.3, k = 16).
    Tcp,
    /// QEM edge collapse keeping original positions (mesh inputs only).
    Qem,
}

impl SelectionMethod {
    /// The method used when none is named.
    pub const DEFAULT: SelectionMethod = SelectionMethod::Neural;

    /// The methods a benchmark compares when none are named (Table 5.1's rows we implement).
    pub const BENCH_DEFAULT: [SelectionMethod; 4] = [
        SelectionMethod::Neural,
        SelectionMethod::Fps,
        SelectionMethod::Random,
        SelectionMethod::Tcp,
    ];

    /// Every method, in the order of [`SelectionMethod::name`]'s listing.
    pub const ALL: [SelectionMethod; 6] = [
        SelectionMethod::Neural,
        SelectionMethod::Sampler,
        SelectionMethod::Fps,
        SelectionMethod::Random,
        SelectionMethod::Tcp,
        SelectionMethod::Qem,
    ];

    /// The method called `name` (as [`SelectionMethod::name`] writes it), if any.
    ///
    /// ```
    /// use meshgnn_models::point_selection::SelectionMethod;
    /// assert_eq!(SelectionMethod::from_name("fps"), Some(SelectionMethod::Fps));
    /// assert_eq!(SelectionMethod::from_name("FPS"), None);
    /// ```
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|method| method.name() == name)
    }

    /// The name used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        match self {
            Self::Neural => "neural",
            Self::Sampler => "sampler",
            Self::Fps => "fps",
            Self::Random => "random",
            Self::Tcp => "tcp",
            Self::Qem => "qem",
        }
    }
}

/// The trained model a learned method reads.
#[derive(Clone, Debug)]
pub enum SelectionModel {
    /// The ch. 5.3 simplifier, for [`SelectionMethod::Neural`].
    Simplifier(PointSimplifier),
    /// The ch. 6 neural mesh simplifier, whose point sampler [`SelectionMethod::Sampler`] runs.
    MeshSimplifier(NeuralMeshSimplifier),
}

impl SelectionModel {
    /// The model `method` reads, from the checkpoint `weights` or else the bundled one;
    /// `None` for the classical methods.
    pub fn for_method(method: SelectionMethod, weights: Option<&Path>) -> Result<Option<Self>> {
        Ok(match method {
            SelectionMethod::Neural => Some(Self::Simplifier(match weights {
                Some(path) => PointSimplifier::load(path)?,
                None => pretrained::load(POINT_SIMPLIFIER_NAME)?,
            })),
            SelectionMethod::Sampler => Some(Self::MeshSimplifier(
                NeuralMeshSimplifier::load_or_bundled(weights)?,
            )),
            _ => None,
        })
    }
}

/// What a method reads: the points, their normals and the mesh they came from, when known.
#[derive(Debug, Clone, Copy)]
pub struct SelectionInput<'a> {
    /// The points, `#P×3` (a mesh's vertices).
    pub points: &'a [[f32; 3]],
    /// Per-point normals, when known (carried to the kept points by the neural method).
    pub normals: Option<&'a [[f32; 3]]>,
    /// The mesh whose vertices `points` are (QEM needs it; the neural method uses its
    /// adjacency).
    pub mesh: Option<&'a TriMesh>,
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

    /// The kept positions: the method's own (refined) or the input `points` at `indices`.
    pub fn kept_points(&self, points: &[[f32; 3]]) -> Vec<[f32; 3]> {
        match &self.points {
            Some(kept) => kept.clone(),
            None => self
                .indices
                .iter()
                .filter_map(|&i| points.get(i as usize).copied())
                .collect(),
        }
    }
}

/// `round(ratio × n)` or `points`, checked to be in `1..=n`; exactly one must be given.
///
/// ```
/// use meshgnn_models::point_selection::target_count;
/// assert_eq!(target_count(10, Some(0.25), None)?, 3); // 2.5 rounds away from 0
/// assert!(target_count(10, None, Some(11)).is_err());
/// # Ok::<(), meshgnn_models::Error>(())
/// ```
pub fn target_count(n: usize, ratio: Option<f64>, points: Option<usize>) -> Result<usize> {
    let invalid = |reason: String| Error::Invalid {
        what: "target".into(),
        reason,
    };
    let count = match (ratio, points) {
        (Some(r), None) => {
            if !(r.is_finite() && r > 0.0 && r <= 1.0) {
                return Err(invalid(format!("--ratio must be in (0, 1], got {r}")));
            }
            (r * n as f64).round() as usize
        }
        (None, Some(p)) => p,
        _ => return Err(invalid("give exactly one of --ratio and --points".into())),
    };
    if count == 0 {
        return Err(invalid(format!(
            "the target keeps 0 of {n} points: raise --ratio or --points"
        )));
    }
    if count > n {
        return Err(invalid(format!(
            "cannot keep {count} points: the input has only {n}"
        )));
    }
    Ok(count)
}

/// Runs `method` on `input` to keep exactly `count` points; `seed` drives every random
/// choice; `model` is the trained model of a learned method
/// ([`SelectionModel::for_method`]).
pub fn select(
    method: SelectionMethod,
    input: &SelectionInput<'_>,
    count: usize,
    seed: u64,
    model: Option<&SelectionModel>,
) -> Result<Selection> {
    let n = input.points.len();
    let invalid = |reason: String| Error::Invalid {
        what: format!("{} selection", method.name()),
        reason,
    };
    if count == 0 || count > n {
        return Err(invalid(format!("cannot keep {count} of {n} points")));
    }
    let start = Instant::now();
    let mut mesh = None;
    let indices = match method {
        SelectionMethod::Neural => {
            let Some(SelectionModel::Simplifier(model)) = model else {
                return Err(invalid(
                    "the neural method needs the point simplifier's weights".into(),
                ));
            };
            return select_neural(model, input, count, seed);
        }
        SelectionMethod::Sampler => {
            let Some(SelectionModel::MeshSimplifier(model)) = model else {
                return Err(invalid(
                    "the sampler needs the neural mesh simplifier's weights".into(),
                ));
            };
            let adjacency = input.mesh.map(vertex_adjacency).transpose()?;
            model.sample_points(input.points, adjacency.as_ref(), count, seed)?
        }
        SelectionMethod::Fps => {
            fast_farthest_point_sampling(input.points, count, FpsStart::Seeded(seed))?
        }
        SelectionMethod::Random => uniform_sampling(n, count, seed)?,
        SelectionMethod::Tcp => {
            if n <= 2 {
                return Err(invalid(format!(
                    "TCP needs at least 3 points for curvature, got {n}"
                )));
            }
            let k = EVALUATION_CURVATURE_NEIGHBOURS.min(n - 1);
            let features = curvature_features(input.points, k)?;
            top_curvature_sampling(&features.mean_curvature, count)?
        }
        SelectionMethod::Qem => {
            let Some(source) = input.mesh else {
                return Err(invalid(
                    "--method qem needs a mesh input (a file with faces); this is a point cloud: use fps, random or tcp".into(),
                ));
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
    input: &SelectionInput<'_>,
    count: usize,
    seed: u64,
) -> Result<Selection> {
    let start = Instant::now();
    let adjacency = match input.mesh {
        Some(mesh) => Some(vertex_adjacency(mesh)?),
        None => None,
    };
    let adjacency_seconds = start.elapsed().as_secs_f64();
    let out = model.simplify(
        input.points,
        input.normals,
        adjacency.as_ref(),
        count,
        &SimplifyOptions {
            seed,
            ..Default::default()
        },
    )?;
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
    use super::*;
    use meshgnn_geometry::icosphere;

    /// An untrained simplifier (random weights): exercises the neural path without the
    /// bundled weights.
    fn random_model() -> SelectionModel {
        let map = candle_nn::VarMap::new();
        let vb = candle_nn::VarBuilder::from_varmap(
            &map,
            candle_core::DType::F32,
            &candle_core::Device::Cpu,
        );
        SelectionModel::Simplifier(PointSimplifier::new(vb, &Default::default()).unwrap())
    }

    fn distinct(indices: &[u32]) -> usize {
        let mut s = indices.to_vec();
        s.sort_unstable();
        s.dedup();
        s.len()
    }

    fn mesh_input(mesh: &TriMesh) -> SelectionInput<'_> {
        SelectionInput {
            points: mesh.vertices(),
            normals: None,
            mesh: Some(mesh),
        }
    }

    fn cloud_input(mesh: &TriMesh) -> SelectionInput<'_> {
        SelectionInput {
            mesh: None,
            ..mesh_input(mesh)
        }
    }

    #[test]
    fn every_method_returns_the_requested_count_of_distinct_indices() {
        let mesh = icosphere(3); // 642 vertices
        let (sphere, cloud) = (mesh_input(&mesh), cloud_input(&mesh));
        let model = random_model();
        for count in [1, 64, 642] {
            for input in [&sphere, &cloud] {
                let s = select(SelectionMethod::Neural, input, count, 7, Some(&model)).unwrap();
                assert_eq!(s.indices.len(), count);
                assert_eq!(distinct(&s.indices), count);
                assert_eq!(s.kept_points(input.points).len(), count);
                let stages: Vec<&str> = s.timings.iter().map(|t| t.0).collect();
                assert_eq!(stages, ["knn", "projector", "selector", "attref"]);
            }
        }
        assert!(select(SelectionMethod::Neural, &sphere, 10, 0, None).is_err());
        // The sampler with the bundled weights, on the mesh and on the bare cloud.
        let sampler = SelectionModel::for_method(SelectionMethod::Sampler, None).unwrap();
        for input in [&sphere, &cloud] {
            for count in [1, 64, 642] {
                let s =
                    select(SelectionMethod::Sampler, input, count, 7, sampler.as_ref()).unwrap();
                assert_eq!(distinct(&s.indices), count);
                let again = select(SelectionMethod::Sampler, input, count, 7, sampler.as_ref());
                assert_eq!(again.unwrap().indices, s.indices, "seeded");
            }
        }
        // Each learned method refuses the other's model.
        assert!(select(SelectionMethod::Sampler, &sphere, 10, 0, Some(&model)).is_err());
        assert!(select(SelectionMethod::Neural, &sphere, 10, 0, sampler.as_ref()).is_err());
        for method in [
            SelectionMethod::Fps,
            SelectionMethod::Random,
            SelectionMethod::Tcp,
            SelectionMethod::Qem,
        ] {
            // a closed mesh keeps at least 4 vertices under QEM
            let smallest = if method == SelectionMethod::Qem { 4 } else { 1 };
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
        let mesh = icosphere(3);
        let sphere = mesh_input(&mesh);
        let s = select(SelectionMethod::Qem, &sphere, 100, 0, None).unwrap();
        let kept = s.mesh.unwrap();
        assert_eq!(kept.vertex_count(), 100);
        for (o, &i) in s.indices.iter().enumerate() {
            assert_eq!(kept.vertices()[o], sphere.points[i as usize]);
        }
        // A closed genus-0 input stays closed: F = 2V − 4.
        assert_eq!(kept.face_count(), 196);
    }

    #[test]
    fn tcp_keeps_points_on_the_sharp_edges_of_a_cube() {
        // Curvature is zero on the faces' interiors and high along the 12 edges; K̄ (eq. 5.3)
        // smooths it over about one grid step (0.1), so every pick lies within a step of an
        // edge (such points are 13 % of the cube's; random picks would miss).
        let cube = meshgnn_geometry::subdivided_cube(20);
        let input = mesh_input(&cube);
        let s = select(SelectionMethod::Tcp, &input, 24, 0, None).unwrap();
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
        let mesh = icosphere(2);
        let err = select(SelectionMethod::Qem, &cloud_input(&mesh), 10, 0, None).unwrap_err();
        assert!(format!("{err:#}").contains("needs a mesh"), "{err:#}");
    }

    #[test]
    fn same_seed_same_selection() {
        let mesh = icosphere(3);
        let sphere = mesh_input(&mesh);
        for method in [SelectionMethod::Fps, SelectionMethod::Random] {
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
