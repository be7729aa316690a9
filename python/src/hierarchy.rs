//! `mesh_hierarchy`: the multi-resolution template of COMA / Neural3DMM / SpiralNet++
//! (`meshgnn_graph::build_hierarchy`, thesis ch. 3.3.4) as numpy arrays and CSR parts, which
//! `meshgnn.mesh_hierarchy` turns into `scipy.sparse.csr_matrix`.

use meshgnn_graph::{CsrMatrix, HierarchyOptions, build_hierarchy, vertex_adjacency};
use numpy::{IntoPyArray, PyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::{index_rows_out, index_vector_out};
use crate::errors::value_error;
use crate::mesh_io::{mesh_out, surface_mesh_in};

/// A CSR matrix as `(data float32, indices int32, indptr int64, (rows, cols))`, the
/// arguments of `scipy.sparse.csr_matrix`.
type CsrParts<'py> = (
    Bound<'py, PyArray1<f32>>,
    Bound<'py, PyArray1<i32>>,
    Bound<'py, PyArray1<i64>>,
    (usize, usize),
);

/// `_mesh_hierarchy(V, F, factors, spiral_lengths, dilations) -> dict` of per-level lists:
/// `vertices`, `faces`, `adjacency`, `spirals`, `spiral_valid`, and per pooling step `down`,
/// `up` (CSR parts). `spiral_lengths`/`dilations`: one value for every level or one per level.
#[pyfunction]
#[pyo3(signature = (v, f, factors, spiral_lengths, dilations, /))]
pub fn mesh_hierarchy<'py>(
    py: Python<'py>,
    v: &Bound<'py, PyAny>,
    f: &Bound<'py, PyAny>,
    factors: Vec<f64>,
    spiral_lengths: Vec<usize>,
    dilations: Vec<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let template = surface_mesh_in(v, f)?;
    let options = HierarchyOptions {
        factors,
        spiral_lengths,
        dilations,
    };
    let (hierarchy, adjacency) = py
        .detach(|| {
            let hierarchy = build_hierarchy(&template, &options)?;
            let adjacency = hierarchy
                .levels
                .iter()
                .map(vertex_adjacency)
                .collect::<meshgnn_graph::Result<Vec<_>>>()?;
            let down = hierarchy.pooling.iter().map(|p| p.down.to_csr());
            let up = hierarchy.pooling.iter().map(|p| p.up.to_csr());
            let down = down.collect::<meshgnn_graph::Result<Vec<_>>>()?;
            let up = up.collect::<meshgnn_graph::Result<Vec<_>>>()?;
            Ok::<_, meshgnn_graph::Error>((hierarchy, (adjacency, down, up)))
        })
        .map_err(|e| value_error("mesh_hierarchy", e))?;
    let (adjacency, down, up) = adjacency;
    let out = PyDict::new(py);
    let (mut vertices, mut faces) = (Vec::new(), Vec::new());
    for level in hierarchy.levels {
        let (v, f) = mesh_out(py, level)?;
        vertices.push(v);
        faces.push(f);
    }
    out.set_item("vertices", vertices)?;
    out.set_item("faces", faces)?;
    let spirals = hierarchy.spirals.iter();
    let spiral_rows = spirals.map(|s| index_rows_out(py, &s.indices, s.length));
    out.set_item("spirals", spiral_rows.collect::<PyResult<Vec<_>>>()?)?;
    let valid = hierarchy.spirals.iter();
    let valid = valid.map(|s| index_vector_out(py, &s.valid));
    out.set_item("spiral_valid", valid.collect::<Vec<_>>())?;
    for (key, matrices) in [("adjacency", adjacency), ("down", down), ("up", up)] {
        let parts = matrices.into_iter().map(|m| csr_parts(py, &m));
        out.set_item(key, parts.collect::<PyResult<Vec<_>>>()?)?;
    }
    Ok(out)
}

/// `matrix` as [`CsrParts`].
fn csr_parts<'py>(py: Python<'py>, matrix: &CsrMatrix) -> PyResult<CsrParts<'py>> {
    let indices = matrix.col_indices().iter().map(|&c| i32::try_from(c));
    let indices = indices
        .collect::<Result<Vec<i32>, _>>()
        .map_err(|e| value_error("sparse matrix column index", e))?;
    let indptr: Vec<i64> = matrix.row_offsets().iter().map(|&o| o as i64).collect();
    Ok((
        matrix.values().to_vec().into_pyarray(py),
        indices.into_pyarray(py),
        indptr.into_pyarray(py),
        (matrix.rows(), matrix.cols()),
    ))
}
