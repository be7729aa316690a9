//! The simplification methods `meshsimplify` offers, each with what it needs besides the mesh,
//! and what one simplification reports: shared by `simplify` (one file or a folder) and
//! `bench` (Table 6.1).
//!
//! `qem` targets faces; `neural` and `pc+remesh` select vertices, so their target becomes a
//! vertex count ([`Target::vertex_count`]).

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use meshgnn_geometry::{
    TangentChartOptions, TriMesh, stdout_line, tangent_chart_triangulation, vertex_normals,
};
use meshgnn_graph::{DecimationOptions, Target, decimate_keeping};
use meshgnn_models::mesh_simplifier::{NeuralMeshSimplifier, NeuralSimplifyOptions};
use meshgnn_models::point_selection::{SelectionInput, SelectionMethod, SelectionModel, select};
use serde_json::{Value, json};

/// Simplification methods.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Quadric error metric edge collapse (Garland & Heckbert 1997).
    Qem,
    /// The neural mesh simplifier of thesis ch. 6: sampled vertices, predicted edges,
    /// classified faces, made edge-manifold.
    Neural,
    /// The ch. 5 route: the point-cloud simplifier keeps vertices, the tangent-chart
    /// triangulation re-meshes them.
    #[value(name = "pc+remesh")]
    PcRemesh,
}

impl Method {
    /// The name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Qem => "qem",
            Self::Neural => "neural",
            Self::PcRemesh => "pc+remesh",
        }
    }
}

/// The options some methods take; [`Simplifier::new`] refuses one given to another method.
#[derive(Clone, Debug, Default)]
pub struct MethodOptions<'a> {
    /// QEM stops before any collapse above this error (input units).
    pub max_error: Option<f64>,
    /// QEM never removes nor moves these input vertices.
    pub keep: Vec<u32>,
    /// Neural: close the holes of at most this many edges.
    pub fill_holes: Option<usize>,
    /// Neural: leave the selected vertices at their input positions (no quadric placement).
    pub keep_positions: bool,
    /// Neural or pc+remesh: weights from a training run instead of the bundled ones.
    pub weights: Option<&'a Path>,
    /// Neural or pc+remesh: seed of their random draws.
    pub seed: u64,
}

/// A method with everything it needs besides the mesh.
pub enum Simplifier {
    Qem {
        options: DecimationOptions,
        keep: Vec<u32>,
    },
    Neural {
        model: Box<NeuralMeshSimplifier>,
        target: Target,
        seed: u64,
        options: NeuralSimplifyOptions,
    },
    PcRemesh {
        model: Box<SelectionModel>,
        target: Target,
        seed: u64,
    },
}

impl Simplifier {
    /// `method` aiming at `target`: checks that every option given belongs to it and loads
    /// its weights; for a learned method, freed memory is kept in the process from then on
    /// (`meshgnn_models::reuse_freed_memory`).
    pub fn new(method: Method, target: Target, options: &MethodOptions) -> Result<Self> {
        let only = |given: bool, option: &str, methods: &str| {
            if given {
                bail!("{option} applies to --method {methods} only");
            }
            Ok(())
        };
        if method != Method::Qem {
            only(options.max_error.is_some(), "--max-error", "qem")?;
            only(!options.keep.is_empty(), "--keep", "qem")?;
        }
        if method != Method::Neural {
            only(options.fill_holes.is_some(), "--fill-holes", "neural")?;
            only(options.keep_positions, "--keep-positions", "neural")?;
        }
        match method {
            Method::Qem => {
                only(
                    options.weights.is_some(),
                    "--weights",
                    "neural or pc+remesh",
                )?;
                Ok(Self::Qem {
                    options: DecimationOptions {
                        target,
                        max_error: options.max_error,
                        ..Default::default()
                    },
                    keep: options.keep.clone(),
                })
            }
            Method::Neural => {
                if let Some(k) = options.fill_holes
                    && k > meshgnn_geometry::MAX_FILLED_HOLE_EDGES
                {
                    bail!(
                        "--fill-holes {k}: fill holes of at most {} edges",
                        meshgnn_geometry::MAX_FILLED_HOLE_EDGES
                    );
                }
                meshgnn_models::reuse_freed_memory();
                let model =
                    NeuralMeshSimplifier::load_or_bundled(options.weights).with_context(|| {
                        match options.weights {
                            Some(path) => {
                                format!("loading the neural simplifier weights {}", path.display())
                            }
                            None => "loading the bundled neural simplifier weights".into(),
                        }
                    })?;
                Ok(Self::Neural {
                    model: Box::new(model),
                    target,
                    seed: options.seed,
                    options: NeuralSimplifyOptions {
                        fill_holes_up_to: options.fill_holes,
                        keep_positions: options.keep_positions,
                    },
                })
            }
            Method::PcRemesh => {
                meshgnn_models::reuse_freed_memory();
                let model = SelectionModel::for_method(SelectionMethod::Neural, options.weights)
                    .with_context(|| match options.weights {
                        Some(path) => {
                            format!(
                                "loading the point-cloud simplifier weights {}",
                                path.display()
                            )
                        }
                        None => "loading the bundled point-cloud simplifier weights".into(),
                    })?
                    .context("the point-cloud simplifier has no model")?;
                Ok(Self::PcRemesh {
                    model: Box::new(model),
                    target,
                    seed: options.seed,
                })
            }
        }
    }

    /// The size this method aims at.
    pub fn target(&self) -> &Target {
        match self {
            Self::Qem { options, .. } => &options.target,
            Self::Neural { target, .. } | Self::PcRemesh { target, .. } => target,
        }
    }

    /// Simplifies `mesh`, reporting progress in [0, 1]: the result and its report.
    pub fn run(&self, mesh: &TriMesh, progress: &mut dyn FnMut(f64)) -> Result<(TriMesh, Outcome)> {
        check_target(self.target(), mesh.face_count())?;
        let start = Instant::now();
        let selected = |simplified: TriMesh, watertightness| {
            let outcome = Outcome {
                input_faces: mesh.face_count(),
                input_vertices: mesh.vertex_count(),
                faces: simplified.face_count(),
                vertices: simplified.vertex_count(),
                seconds: start.elapsed().as_secs_f64(),
                error: None,
                stop_reason: "target_reached",
                welded: false,
                watertightness,
            };
            (simplified, outcome)
        };
        match self {
            Self::Qem { options, keep } => {
                let result = decimate_keeping(mesh, options, keep, progress)?;
                let outcome = Outcome {
                    input_faces: result.input_faces,
                    input_vertices: result.input_vertices,
                    faces: result.mesh.face_count(),
                    vertices: result.mesh.vertex_count(),
                    seconds: start.elapsed().as_secs_f64(),
                    error: Some(result.error_distance),
                    stop_reason: result.stop_reason.as_str(),
                    welded: result.welded,
                    watertightness: None,
                };
                Ok((result.mesh, outcome))
            }
            Self::Neural {
                model,
                target,
                seed,
                options,
            } => {
                let result = model.simplify_to(mesh, target, *seed, options, progress)?;
                let watertightness = Watertightness {
                    wa_raw: result.wa_raw,
                    wa: result.wa,
                    holes: result.holes,
                };
                Ok(selected(result.mesh, Some(watertightness)))
            }
            Self::PcRemesh {
                model,
                target,
                seed,
            } => {
                let normals = vertex_normals(mesh);
                let input = SelectionInput {
                    points: mesh.vertices(),
                    normals: Some(&normals),
                    mesh: Some(mesh),
                };
                let kept = target.vertex_count(mesh);
                let selection = select(SelectionMethod::Neural, &input, kept, *seed, Some(model))?;
                progress(0.5);
                let kept_normals: Vec<[f32; 3]> = selection
                    .indices
                    .iter()
                    .map(|&i| normals[i as usize])
                    .collect();
                let remeshed = tangent_chart_triangulation(
                    &selection.kept_points(mesh.vertices()),
                    Some(&kept_normals),
                    &TangentChartOptions::default(),
                )
                .context("re-meshing the kept points")?;
                progress(1.0);
                Ok(selected(remeshed.mesh, None))
            }
        }
    }
}

/// Fails unless `target` keeps between 1 and all of the input's `faces`.
pub fn check_target(target: &Target, faces: usize) -> Result<()> {
    match *target {
        Target::Faces(0) => bail!("--faces 0: keep at least 1 face"),
        Target::Faces(n) if n > faces => bail!(
            "--faces {n} is more than the input's {faces} faces: choose at most {faces} \
             (or copy the file)"
        ),
        Target::Ratio(r) if (r * faces as f64).round() < 1.0 => bail!(
            "--ratio {r} keeps 0 of the input's {faces} faces: raise it to at least {:.3e}",
            1.0 / faces as f64
        ),
        _ => Ok(()),
    }
}

/// The neural method's watertightness figures.
pub struct Watertightness {
    pub wa_raw: f64,
    pub wa: f64,
    pub holes: usize,
}

/// What one simplification reports.
pub struct Outcome {
    pub input_faces: usize,
    pub input_vertices: usize,
    pub faces: usize,
    pub vertices: usize,
    /// QEM's largest collapse error (input units).
    pub error: Option<f64>,
    pub seconds: f64,
    pub stop_reason: &'static str,
    pub welded: bool,
    pub watertightness: Option<Watertightness>,
}

impl Outcome {
    /// The `--json` keys; a folder run adds the file paths.
    pub fn to_json(&self, files: Option<(&Path, &Path)>) -> Value {
        let mut value = json!({
            "input_faces": self.input_faces,
            "output_faces": self.faces,
            "error": self.error,
            "seconds": self.seconds,
            "stop_reason": self.stop_reason,
        });
        if let Some(map) = value.as_object_mut() {
            if let Some(w) = &self.watertightness {
                map.insert("wa_raw".into(), json!(w.wa_raw));
                map.insert("wa".into(), json!(w.wa));
                map.insert("holes".into(), json!(w.holes));
            }
            if let Some((input, output)) = files {
                map.insert("input".into(), json!(input.display().to_string()));
                map.insert("output".into(), json!(output.display().to_string()));
            }
        }
        value
    }

    /// Two lines of text for a person.
    pub fn print(&self, input: &Path, output: &Path) {
        stdout_line!(
            "{}: {} faces, {} vertices -> {}: {} faces, {} vertices ({}{})",
            input.display(),
            self.input_faces,
            self.input_vertices,
            output.display(),
            self.faces,
            self.vertices,
            self.stop_reason,
            if self.welded { ", welded" } else { "" },
        );
        match (&self.watertightness, self.error) {
            (Some(w), _) => stdout_line!(
                "WA {:.2}% raw, {:.2}% after the manifold pass, {} holes, {:.3} s",
                w.wa_raw,
                w.wa,
                w.holes,
                self.seconds
            ),
            (None, Some(error)) => {
                stdout_line!("error {error:.3e} (input units), {:.3} s", self.seconds)
            }
            (None, None) => stdout_line!("{:.3} s", self.seconds),
        }
    }
}
