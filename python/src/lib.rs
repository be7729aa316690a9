//! `meshgnn._native`: the Rust side of the `meshgnn` Python package (python/meshgnn/ wraps
//! it and documents the API in docs/python.md). Every function takes numpy arrays, releases
//! the GIL while it computes, and raises `ValueError`/`OSError` with the command-line tools'
//! one-line messages instead of crashing the interpreter.

mod arrays;
mod errors;
mod hierarchy;
mod mesh_io;
mod metrics;
mod point_operators;
mod point_simplify;
mod simplify;

use pyo3::prelude::*;

/// The extension module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(mesh_io::read_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(mesh_io::write_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(mesh_io::read_points, m)?)?;
    m.add_function(wrap_pyfunction!(mesh_io::write_points, m)?)?;
    m.add_function(wrap_pyfunction!(simplify::simplify, m)?)?;
    m.add_function(wrap_pyfunction!(hierarchy::mesh_hierarchy, m)?)?;
    m.add_function(wrap_pyfunction!(
        point_operators::farthest_point_sampling,
        m
    )?)?;
    m.add_function(wrap_pyfunction!(point_operators::weighted_sampling, m)?)?;
    m.add_function(wrap_pyfunction!(point_operators::knn, m)?)?;
    m.add_function(wrap_pyfunction!(point_operators::chamfer, m)?)?;
    m.add_function(wrap_pyfunction!(metrics::point_cloud_metrics, m)?)?;
    m.add_function(wrap_pyfunction!(metrics::mesh_metrics, m)?)?;
    m.add_function(wrap_pyfunction!(point_simplify::point_simplify, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
