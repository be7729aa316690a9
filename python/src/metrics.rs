//! The evaluation metrics of `pcsimplify eval` and `meshsimplify eval` on numpy arrays, as
//! dicts with the same keys as their `--json` output.

use meshgnn_losses::metrics::{
    EVALUATION_CURVATURE_NEIGHBOURS, MESH_EVALUATION_SAMPLES, mesh_evaluation,
    point_cloud_evaluation,
};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::FloatRows;
use crate::errors::value_error;
use crate::mesh_io::mesh_in;

/// `point_cloud_metrics(original, simplified, k=16) -> dict`: `cd`, `nc`, `ce`, `re`, `sdm`
/// of the simplified cloud against the original (thesis ch. 5.4, eqs. 5.6-5.9), both
/// normalised by the original's unit sphere, curvature from `k` neighbours.
#[pyfunction]
#[pyo3(signature = (original, simplified, /, k=EVALUATION_CURVATURE_NEIGHBOURS))]
pub fn point_cloud_metrics<'py>(
    py: Python<'py>,
    original: &Bound<'py, PyAny>,
    simplified: &Bound<'py, PyAny>,
    k: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let original = FloatRows::extract(original, "original", Some(3))?;
    let simplified = FloatRows::extract(simplified, "simplified", Some(3))?;
    let (a, b) = (original.points(), simplified.points());
    let e = py
        .detach(|| point_cloud_evaluation(a, b, k))
        .map_err(|e| value_error("point_cloud_metrics", e))?;
    let out = PyDict::new(py);
    for (key, value) in [
        ("cd", e.cd),
        ("nc", e.nc),
        ("ce", e.ce),
        ("re", e.re),
        ("sdm", e.sdm),
        ("sdm_nearest", e.sdm_nearest),
    ] {
        out.set_item(key, value)?;
    }
    Ok(out)
}

/// `mesh_metrics(V, F, V_simplified, F_simplified, samples=50000, seed=0) -> dict`: `cd`,
/// `hausdorff`, `ne`, `wa`, `le`, `holes`, `edge_manifold` of the simplified mesh against the
/// original (thesis ch. 6.4; `samples` surface samples per mesh from `seed`).
#[pyfunction]
#[pyo3(signature = (v, f, v_simplified, f_simplified, /, samples=MESH_EVALUATION_SAMPLES, seed=0))]
pub fn mesh_metrics<'py>(
    py: Python<'py>,
    v: &Bound<'py, PyAny>,
    f: &Bound<'py, PyAny>,
    v_simplified: &Bound<'py, PyAny>,
    f_simplified: &Bound<'py, PyAny>,
    samples: usize,
    seed: u64,
) -> PyResult<Bound<'py, PyDict>> {
    let original = mesh_in(v, f)?;
    let simplified = mesh_in(v_simplified, f_simplified)?;
    let e = py
        .detach(|| mesh_evaluation(&original, &simplified, samples, seed))
        .map_err(|e| value_error("mesh_metrics", e))?;
    let out = PyDict::new(py);
    for (key, value) in [
        ("cd", e.cd),
        ("hausdorff", e.hausdorff),
        ("ne", e.ne),
        ("wa", e.wa),
        ("le", e.le),
    ] {
        out.set_item(key, value)?;
    }
    out.set_item("holes", e.holes)?;
    out.set_item("edge_manifold", e.edge_manifold)?;
    Ok(out)
}
