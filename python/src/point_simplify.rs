//! `point_simplify`: the point-cloud simplifiers of `pcsimplify simplify`
//! (`meshgnn_models::point_selection`: the learned simplifier of thesis ch. 5.3 and the point
//! sampler of ch. 6 with their bundled weights, and the FPS, random, TCP and QEM baselines).

use std::path::{Path, PathBuf};

use meshgnn_geometry::{TriMesh, check_input_points};
use meshgnn_models::point_selection::{
    self, SelectionInput, SelectionMethod, SelectionModel, target_count,
};
use numpy::{PyArray1, PyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::arrays::{ArrayPair, FloatRows, float_rows_out, index_vector_out, triangles};
use crate::errors::{geometry_error, value_error};

/// `point_simplify(X, *, ratio=None, points=None, method="neural", seed=0, faces_of=None,
/// weights=None) -> (indices int64 (k,), kept float32 (k, 3))`: keeps `round(ratio·n)` or
/// `points` of the rows of `X`. `faces_of`: the faces when `X` are a mesh's vertices (QEM
/// needs them; the neural method and the sampler then use the mesh adjacency). `weights`: a
/// checkpoint of the learned method instead of the bundled one. `kept` are the kept points, moved by the neural
/// method's refinement (eq. 5.5), else `X[indices]`.
#[pyfunction]
#[pyo3(signature = (x, /, *, ratio=None, points=None, method="neural", seed=0, faces_of=None, weights=None))]
#[allow(clippy::too_many_arguments)]
pub fn point_simplify<'py>(
    py: Python<'py>,
    x: &Bound<'py, PyAny>,
    ratio: Option<f64>,
    points: Option<usize>,
    method: &str,
    seed: u64,
    faces_of: Option<&Bound<'py, PyAny>>,
    weights: Option<PathBuf>,
) -> PyResult<ArrayPair<'py, PyArray1<i64>, PyArray2<f32>>> {
    let method = SelectionMethod::from_name(method).ok_or_else(|| {
        let names: Vec<_> = SelectionMethod::ALL.iter().map(|m| m.name()).collect();
        PyValueError::new_err(format!("method={method:?}: choose one of {names:?}"))
    })?;
    let rows = FloatRows::extract(x, "X", Some(3))?;
    let cloud = rows.points();
    check_input_points(Path::new("X"), cloud).map_err(geometry_error)?;
    let mesh = faces_of
        .map(|f| {
            let faces = triangles(f, "faces_of")?;
            TriMesh::new(cloud.to_vec(), faces).map_err(|e| value_error("X, faces_of", e))
        })
        .transpose()?;
    let count =
        target_count(cloud.len(), ratio, points).map_err(|e| value_error("point_simplify", e))?;
    let selection = py
        .detach(|| {
            let model = SelectionModel::for_method(method, weights.as_deref())?;
            let input = SelectionInput {
                points: cloud,
                normals: None,
                mesh: mesh.as_ref(),
            };
            point_selection::select(method, &input, count, seed, model.as_ref())
        })
        .map_err(|e| value_error("point_simplify", e))?;
    let kept = selection
        .points
        .clone()
        .unwrap_or_else(|| selection.kept_points(cloud));
    Ok((
        index_vector_out(py, &selection.indices),
        float_rows_out(py, kept)?,
    ))
}
