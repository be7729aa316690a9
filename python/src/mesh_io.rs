//! Reading and writing meshes and point clouds (OBJ, PLY, OFF, glTF/GLB, XYZ; the
//! format follows the extension), through the same checked readers and atomic writers as
//! the command-line tools.

use std::path::{Path, PathBuf};

use meshgnn_geometry::{
    InputUse, PointCloud, TriMesh, check_input_mesh, read_input_mesh, read_input_point_cloud,
    write_point_cloud,
};
use numpy::PyArray2;
use pyo3::prelude::*;

use crate::arrays::{ArrayPair, FloatRows, float_rows_out, index_rows_out, triangles};
use crate::errors::{geometry_error, value_error};

/// `read_mesh(path) -> (V, F)`: vertices float32 `(n, 3)` and faces int64 `(m, 3)`
/// (polygons fan-triangulated; a file of points only gives `m = 0`).
#[pyfunction]
pub fn read_mesh<'py>(
    py: Python<'py>,
    path: PathBuf,
) -> PyResult<ArrayPair<'py, PyArray2<f32>, PyArray2<i64>>> {
    let mesh = py
        .detach(|| read_input_mesh(&path, InputUse::Points))
        .map_err(geometry_error)?;
    mesh_out(py, mesh)
}

/// `write_mesh(path, V, F)`: writes atomically (a temporary beside `path`, then a rename).
#[pyfunction]
#[pyo3(signature = (path, v, f, /))]
pub fn write_mesh(
    py: Python<'_>,
    path: PathBuf,
    v: &Bound<'_, PyAny>,
    f: &Bound<'_, PyAny>,
) -> PyResult<()> {
    let mesh = mesh_in(v, f)?;
    py.detach(|| meshgnn_geometry::write_mesh(&path, &mesh))
        .map_err(geometry_error)
}

/// `read_points(path) -> X`: the vertices of any mesh or point-cloud file, float32 `(n, 3)`.
#[pyfunction]
pub fn read_points<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyArray2<f32>>> {
    let cloud = py
        .detach(|| read_input_point_cloud(&path))
        .map_err(geometry_error)?;
    float_rows_out(py, cloud.into_parts().0)
}

/// `write_points(path, X)`: writes the points (PLY, OBJ, OFF or XYZ) atomically.
#[pyfunction]
#[pyo3(signature = (path, x, /))]
pub fn write_points(py: Python<'_>, path: PathBuf, x: &Bound<'_, PyAny>) -> PyResult<()> {
    let points = FloatRows::extract(x, "X", Some(3))?;
    let cloud = PointCloud::new(points.points().to_vec()).map_err(|e| value_error("X", e))?;
    py.detach(|| write_point_cloud(&path, &cloud))
        .map_err(geometry_error)
}

/// The mesh of the arrays `v: (n, 3)` and `f: (m, 3)` (arguments `V` and `F`).
pub fn mesh_in(v: &Bound<'_, PyAny>, f: &Bound<'_, PyAny>) -> PyResult<TriMesh> {
    let vertices = FloatRows::extract(v, "V", Some(3))?;
    let faces = triangles(f, "F")?;
    TriMesh::new(vertices.points().to_vec(), faces).map_err(|e| value_error("V, F", e))
}

/// [`mesh_in`] checked to hold a surface (faces of positive area, supported coordinates),
/// as the apps check a mesh they simplify; errors name `V, F`.
pub fn surface_mesh_in(v: &Bound<'_, PyAny>, f: &Bound<'_, PyAny>) -> PyResult<TriMesh> {
    let mesh = mesh_in(v, f)?;
    check_input_mesh(Path::new("V, F"), &mesh, InputUse::Surface).map_err(geometry_error)?;
    Ok(mesh)
}

/// `mesh` as `(V, F)` arrays.
pub fn mesh_out<'py>(
    py: Python<'py>,
    mesh: TriMesh,
) -> PyResult<ArrayPair<'py, PyArray2<f32>, PyArray2<i64>>> {
    let (vertices, triangles, ..) = mesh.into_parts();
    Ok((
        float_rows_out(py, vertices)?,
        index_rows_out(py, triangles.as_flattened(), 3)?,
    ))
}
