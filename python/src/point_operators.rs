//! Point-set operators on numpy arrays: farthest point sampling, weighted sampling, k nearest
//! neighbours and the Chamfer distance (`meshgnn_graph`, `meshgnn_losses::metrics`).

use meshgnn_graph::{
    FpsStart, farthest_point_sampling as exact_fps, fast_farthest_point_sampling, knn_graph,
    knn_query,
};
use meshgnn_losses::metrics::chamfer_distance;
use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::{ArrayPair, FloatRows, float_vector, index_rows_out, index_vector_out};
use crate::errors::value_error;

/// `farthest_point_sampling(X, k, start=0) -> int64 (k,)`: FPS over the rows of `X: (n, d)`,
/// any `d` (3-d points go through the kd-tree pruned FPS, same picks as the exact one).
#[pyfunction]
#[pyo3(signature = (x, k, /, start=0))]
pub fn farthest_point_sampling<'py>(
    py: Python<'py>,
    x: &Bound<'py, PyAny>,
    k: usize,
    start: u32,
) -> PyResult<Bound<'py, PyArray1<i64>>> {
    let points = FloatRows::extract(x, "X", None)?;
    let (values, dim, as_points) = (points.values(), points.dim, points.points());
    let picked = py
        .detach(|| match dim {
            3 => fast_farthest_point_sampling(as_points, k, FpsStart::Index(start)),
            _ => exact_fps(values, dim, k, FpsStart::Index(start)),
        })
        .map_err(|e| value_error("farthest_point_sampling", e))?;
    Ok(index_vector_out(py, &picked))
}

/// `weighted_sampling(w, k, seed=0) -> int64 (k,)`: `k` distinct indices drawn with
/// probability proportional to `w` (thesis eq. 6.4, Efraimidis–Spirakis keys).
#[pyfunction]
#[pyo3(signature = (w, k, /, seed=0))]
pub fn weighted_sampling<'py>(
    py: Python<'py>,
    w: &Bound<'py, PyAny>,
    k: usize,
    seed: u64,
) -> PyResult<Bound<'py, PyArray1<i64>>> {
    let weights = float_vector(w, "w")?;
    let picked = py
        .detach(|| meshgnn_graph::weighted_sampling(&weights, k, seed))
        .map_err(|e| value_error("weighted_sampling", e))?;
    Ok(index_vector_out(py, &picked))
}

/// `knn(X, k, queries=None) -> (indices int64 (q, k), squared_distances float32 (q, k))`:
/// the `k` nearest rows of `X: (n, 3)` to each query, nearest first, ties by index; without
/// `queries`, each point's `k` nearest *other* points.
#[pyfunction]
#[pyo3(signature = (x, k, /, queries=None))]
pub fn knn<'py>(
    py: Python<'py>,
    x: &Bound<'py, PyAny>,
    k: usize,
    queries: Option<&Bound<'py, PyAny>>,
) -> PyResult<ArrayPair<'py, PyArray2<i64>, PyArray2<f32>>> {
    let points = FloatRows::extract(x, "X", Some(3))?;
    let queries = queries
        .map(|q| FloatRows::extract(q, "queries", Some(3)))
        .transpose()?;
    let (points, queries) = (points.points(), queries.as_ref().map(FloatRows::points));
    let neighbours = py
        .detach(|| match queries {
            Some(q) => knn_query(q, points, k),
            None => knn_graph(points, k),
        })
        .map_err(|e| value_error("knn", e))?;
    let rows = neighbours.indices.len().checked_div(k).unwrap_or(0);
    Ok((
        index_rows_out(py, &neighbours.indices, k)?,
        numpy::IntoPyArray::into_pyarray(neighbours.squared_distances, py).reshape([rows, k])?,
    ))
}

/// `chamfer(A, B) -> dict`: eq. 5.6 in both directions (squared distances): `forward_sum`,
/// `reverse_sum`, `forward_mean`, `reverse_mean`, and `mean` = `forward_mean + reverse_mean`
/// (the CD of the evaluations, independent of the point counts).
#[pyfunction]
#[pyo3(signature = (a, b, /))]
pub fn chamfer<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    b: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyDict>> {
    let a = FloatRows::extract(a, "A", Some(3))?;
    let b = FloatRows::extract(b, "B", Some(3))?;
    let (a, b) = (a.points(), b.points());
    let cd = py
        .detach(|| chamfer_distance(a, b))
        .map_err(|e| value_error("chamfer", e))?;
    let out = PyDict::new(py);
    out.set_item("forward_sum", cd.forward_sum)?;
    out.set_item("reverse_sum", cd.reverse_sum)?;
    out.set_item("forward_mean", cd.forward_mean)?;
    out.set_item("reverse_mean", cd.reverse_mean)?;
    out.set_item("mean", cd.symmetric_mean())?;
    Ok(out)
}
