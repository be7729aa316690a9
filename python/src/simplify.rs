//! `simplify`: QEM edge collapse (`meshgnn_graph::decimate_keeping`, the engine of `meshsimplify
//! simplify`) or the neural mesh simplifier of thesis ch. 6 (`NeuralMeshSimplifier`, bundled
//! weights) on numpy arrays.

use std::path::PathBuf;

use meshgnn_graph::{DecimationOptions, Target, decimate_keeping};
use meshgnn_models::mesh_simplifier::{NeuralMeshSimplifier, NeuralSimplifyOptions};
use numpy::IntoPyArray;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::arrays::{index_vector, index_vector_out};
use crate::errors::value_error;
use crate::mesh_io::{mesh_out, surface_mesh_in};

/// `simplify(V, F, *, ratio=None, faces=None, method="qem", max_error=None, keep=None, seed=0,
/// weights=None, fill_holes=None, keep_positions=False, return_vertex_map=False,
/// return_info=False) -> (V', F'[,
/// vertex_map][, info])`: exactly one of `ratio` (of the faces, in (0, 1]) and `faces` (a count
/// in 1..=m). `vertex_map[i]` is the output vertex input vertex `i` was merged into (QEM) or
/// kept as (neural; -1 for a vertex not kept); `info` holds the keys of `meshsimplify simplify
/// --json` (`input_faces`, `output_faces`, `error`, `stop_reason`, and `collapses` for QEM,
/// `wa_raw`, `wa`, `holes` for neural). `max_error` and `keep` (input vertices never removed
/// nor moved, e.g. landmarks: the CLI's `--keep`) are QEM's; `seed`, `weights` (a checkpoint
/// instead of the bundled weights), `fill_holes` (close holes of at most that many edges) and
/// `keep_positions` (leave the selected vertices where the network picked them instead of at
/// their regions' quadric optima) the neural method's.
#[pyfunction]
#[pyo3(signature = (v, f, /, *, ratio=None, faces=None, method="qem", max_error=None, keep=None, seed=0, weights=None, fill_holes=None, keep_positions=false, return_vertex_map=false, return_info=false))]
#[allow(clippy::too_many_arguments)]
pub fn simplify<'py>(
    py: Python<'py>,
    v: &Bound<'py, PyAny>,
    f: &Bound<'py, PyAny>,
    ratio: Option<f64>,
    faces: Option<usize>,
    method: &str,
    max_error: Option<f64>,
    keep: Option<&Bound<'py, PyAny>>,
    seed: u64,
    weights: Option<PathBuf>,
    fill_holes: Option<usize>,
    keep_positions: bool,
    return_vertex_map: bool,
    return_info: bool,
) -> PyResult<Bound<'py, PyTuple>> {
    let neural = match method {
        "qem" => false,
        "neural" => true,
        other => {
            return Err(PyValueError::new_err(format!(
                "method={other:?}: choose \"qem\" or \"neural\""
            )));
        }
    };
    let refuse = |given: bool, option: &str| {
        if given {
            Err(PyValueError::new_err(format!(
                "{option}= applies to method=\"{}\" only",
                if neural { "qem" } else { "neural" }
            )))
        } else {
            Ok(())
        }
    };
    if neural {
        refuse(max_error.is_some(), "max_error")?;
        refuse(keep.is_some(), "keep")?;
    } else {
        refuse(seed != 0, "seed")?;
        refuse(weights.is_some(), "weights")?;
        refuse(fill_holes.is_some(), "fill_holes")?;
        refuse(keep_positions, "keep_positions")?;
    }
    if let Some(e) = max_error
        && !(e >= 0.0 && e.is_finite())
    {
        return Err(PyValueError::new_err(format!(
            "max_error={e}: must be a finite distance >= 0"
        )));
    }
    if let Some(k) = fill_holes
        && k > meshgnn_geometry::MAX_FILLED_HOLE_EDGES
    {
        return Err(PyValueError::new_err(format!(
            "fill_holes={k}: fill holes of at most {} edges",
            meshgnn_geometry::MAX_FILLED_HOLE_EDGES
        )));
    }
    let mesh = surface_mesh_in(v, f)?;
    let target = target(ratio, faces, mesh.face_count())?;
    let info = PyDict::new(py);
    info.set_item("input_faces", mesh.face_count())?;
    let (simplified, map) = if neural {
        let result = py
            .detach(|| {
                NeuralMeshSimplifier::load_or_bundled(weights.as_deref())?.simplify_to(
                    &mesh,
                    &target,
                    seed,
                    &NeuralSimplifyOptions {
                        fill_holes_up_to: fill_holes,
                        keep_positions,
                    },
                    &mut |_| {},
                )
            })
            .map_err(|e| value_error("simplify", e))?;
        info.set_item("output_faces", result.mesh.face_count())?;
        info.set_item("error", py.None())?;
        info.set_item("stop_reason", "target_reached")?;
        info.set_item("wa_raw", result.wa_raw)?;
        info.set_item("wa", result.wa)?;
        info.set_item("holes", result.holes)?;
        let map = return_vertex_map.then(|| {
            let mut map = vec![-1i64; mesh.vertex_count()];
            for (output, &input) in result.vertex_map.iter().enumerate() {
                map[input as usize] = output as i64;
            }
            map.into_pyarray(py)
        });
        (result.mesh, map)
    } else {
        let options = DecimationOptions {
            target,
            max_error,
            ..Default::default()
        };
        let keep = keep.map(|k| index_vector(k, "keep")).transpose()?;
        let keep = keep.as_deref().unwrap_or_default();
        let result = py
            .detach(|| decimate_keeping(&mesh, &options, keep, &mut |_| {}))
            .map_err(|e| value_error("simplify", e))?;
        info.set_item("output_faces", result.mesh.face_count())?;
        info.set_item("error", result.error_distance)?;
        info.set_item("stop_reason", result.stop_reason.as_str())?;
        info.set_item("collapses", result.collapses)?;
        let map = return_vertex_map.then(|| index_vector_out(py, &result.vertex_map));
        (result.mesh, map)
    };
    let (vertices, triangles) = mesh_out(py, simplified)?;
    let mut out = vec![vertices.into_any(), triangles.into_any()];
    out.extend(map.map(Bound::into_any));
    if return_info {
        out.push(info.into_any());
    }
    PyTuple::new(py, out)
}

/// The decimation target of `ratio` or `faces` (exactly one), keeping 1 to all of the
/// input's `face_count` faces.
fn target(ratio: Option<f64>, faces: Option<usize>, face_count: usize) -> PyResult<Target> {
    let fail = |message: String| Err(PyValueError::new_err(message));
    match (ratio, faces) {
        (Some(r), None) if !(r > 0.0 && r <= 1.0) => fail(format!("ratio={r} is outside (0, 1]")),
        (Some(r), None) if (r * face_count as f64).round() < 1.0 => fail(format!(
            "ratio={r} keeps 0 of the input's {face_count} faces: raise it to at least {:.3e}",
            1.0 / face_count as f64
        )),
        (Some(r), None) => Ok(Target::Ratio(r)),
        (None, Some(0)) => fail("faces=0: keep at least 1 face".into()),
        (None, Some(n)) if n > face_count => fail(format!(
            "faces={n} is more than the input's {face_count} faces: choose at most {face_count}"
        )),
        (None, Some(n)) => Ok(Target::Faces(n)),
        _ => fail("give exactly one of ratio= and faces=".into()),
    }
}
