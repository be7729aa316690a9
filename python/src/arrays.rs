//! numpy arrays in and out. Positions arrive as float32 or float64 `(n, d)` arrays and are
//! borrowed, not copied, when they already are C-contiguous float32; index arrays arrive as
//! int32 or int64. Results leave as fresh arrays that take over the Rust buffer (no copy):
//! positions float32 (the precision every operator computes in), indices int64 (what numpy
//! and PyTorch index with).

use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// Two arrays returned together, e.g. `(V, F)`.
pub type ArrayPair<'py, A, B> = (Bound<'py, A>, Bound<'py, B>);

/// The rows of a float `(n, d)` array as row-major `f32`.
pub struct FloatRows<'py> {
    values: Values<'py>,
    /// Columns per row `d`.
    pub dim: usize,
}

enum Values<'py> {
    /// A C-contiguous float32 array, read in place.
    Borrowed(PyReadonlyArray2<'py, f32>),
    /// Any other layout or float64, converted once.
    Owned(Vec<f32>),
}

impl<'py> FloatRows<'py> {
    /// Reads `array` (argument `name`) as a float32/float64 `(n, d)` array, `d == dim` when
    /// given. A float64 value beyond the float32 range becomes infinite, which the operators
    /// reject as non-finite.
    pub fn extract(array: &Bound<'py, PyAny>, name: &str, dim: Option<usize>) -> PyResult<Self> {
        let (values, shape) = if let Ok(a) = array.extract::<PyReadonlyArray2<'py, f32>>() {
            let shape = [a.shape()[0], a.shape()[1]];
            if a.is_c_contiguous() {
                (Values::Borrowed(a), shape)
            } else {
                (Values::Owned(a.as_array().iter().copied().collect()), shape)
            }
        } else if let Ok(a) = array.extract::<PyReadonlyArray2<'py, f64>>() {
            let shape = [a.shape()[0], a.shape()[1]];
            let values = a.as_array().iter().map(|&x| x as f32).collect();
            (Values::Owned(values), shape)
        } else {
            return Err(PyValueError::new_err(format!(
                "{name}: expected a float32 or float64 array of shape (n, {}), got {}",
                dim.map_or_else(|| "d".to_string(), |d| d.to_string()),
                describe(array)
            )));
        };
        if let Some(d) = dim
            && shape[1] != d
        {
            return Err(PyValueError::new_err(format!(
                "{name}: expected shape (n, {d}), got ({}, {})",
                shape[0], shape[1]
            )));
        }
        Ok(Self {
            values,
            dim: shape[1],
        })
    }

    /// Every value, row-major.
    pub fn values(&self) -> &[f32] {
        match &self.values {
            // Borrowed only when C-contiguous, so the slice always exists.
            Values::Borrowed(a) => a.as_slice().unwrap_or_default(),
            Values::Owned(v) => v,
        }
    }

    /// The rows as 3-d points (`dim == 3` was asked for at extraction).
    pub fn points(&self) -> &[[f32; 3]] {
        self.values().as_chunks::<3>().0
    }
}

/// Reads `array` (argument `name`) as an int32/int64 `(n, 3)` array of vertex indices.
/// Negative or larger-than-u32 entries are errors naming the row; the range against the
/// vertex count is checked by the mesh constructor.
pub fn triangles(array: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<[u32; 3]>> {
    let (values, shape): (Vec<i64>, [usize; 2]) =
        if let Ok(a) = array.extract::<PyReadonlyArray2<'_, i64>>() {
            (
                a.as_array().iter().copied().collect(),
                [a.shape()[0], a.shape()[1]],
            )
        } else if let Ok(a) = array.extract::<PyReadonlyArray2<'_, i32>>() {
            let values = a.as_array().iter().map(|&x| i64::from(x)).collect();
            (values, [a.shape()[0], a.shape()[1]])
        } else {
            return Err(PyValueError::new_err(format!(
                "{name}: expected an int32 or int64 array of shape (m, 3), got {}",
                describe(array)
            )));
        };
    if shape[1] != 3 {
        return Err(PyValueError::new_err(format!(
            "{name}: expected shape (m, 3), got ({}, {})",
            shape[0], shape[1]
        )));
    }
    let (rows, _) = values.as_chunks::<3>();
    rows.iter()
        .enumerate()
        .map(|(row, corners)| {
            let mut out = [0u32; 3];
            for (o, &c) in out.iter_mut().zip(corners) {
                *o = u32::try_from(c).map_err(|_| {
                    PyValueError::new_err(format!(
                        "{name}: face {row} has vertex index {c}, outside 0..{}",
                        u32::MAX
                    ))
                })?;
            }
            Ok(out)
        })
        .collect()
}

/// Reads `array` (argument `name`) as vertex indices: an int32/int64 vector or a sequence of
/// ints. A negative or larger-than-u32 entry is an error naming it; the range against the
/// vertex count is checked by the operator.
pub fn index_vector(array: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<u32>> {
    let values: Vec<i64> = if let Ok(a) = array.extract::<PyReadonlyArray1<'_, i64>>() {
        a.as_array().to_vec()
    } else if let Ok(a) = array.extract::<PyReadonlyArray1<'_, i32>>() {
        a.as_array().iter().map(|&x| i64::from(x)).collect()
    } else if let Ok(list) = array.extract::<Vec<i64>>() {
        list
    } else {
        return Err(PyValueError::new_err(format!(
            "{name}: expected an int32 or int64 array of shape (k,) or a sequence of ints, got {}",
            describe(array)
        )));
    };
    values
        .iter()
        .enumerate()
        .map(|(i, &v)| {
            u32::try_from(v).map_err(|_| {
                PyValueError::new_err(format!("{name}: entry {i} is {v}, not a vertex index"))
            })
        })
        .collect()
}

/// Reads `array` (argument `name`) as a float32/float64 vector.
pub fn float_vector(array: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<f32>> {
    if let Ok(a) = array.extract::<PyReadonlyArray1<'_, f32>>() {
        Ok(a.as_array().to_vec())
    } else if let Ok(a) = array.extract::<PyReadonlyArray1<'_, f64>>() {
        Ok(a.as_array().iter().map(|&x| x as f32).collect())
    } else {
        Err(PyValueError::new_err(format!(
            "{name}: expected a float32 or float64 array of shape (n,), got {}",
            describe(array)
        )))
    }
}

/// `rows` as a float32 `(n, N)` array, taking over the buffer.
pub fn float_rows_out<'py, const N: usize>(
    py: Python<'py>,
    rows: Vec<[f32; N]>,
) -> PyResult<Bound<'py, PyArray2<f32>>> {
    let n = rows.len();
    rows.into_flattened().into_pyarray(py).reshape([n, N])
}

/// `values` (`n × width` row-major) as an int64 `(n, width)` array.
pub fn index_rows_out<'py>(
    py: Python<'py>,
    values: &[u32],
    width: usize,
) -> PyResult<Bound<'py, PyArray2<i64>>> {
    let n = values.len().checked_div(width).unwrap_or(0);
    index_vector_out(py, values).reshape([n, width])
}

/// `values` as an int64 vector.
pub fn index_vector_out<'py>(py: Python<'py>, values: &[u32]) -> Bound<'py, PyArray1<i64>> {
    let wide: Vec<i64> = values.iter().map(|&v| i64::from(v)).collect();
    wide.into_pyarray(py)
}

/// What `array` is, for an error message: its dtype and shape, or its Python type.
fn describe(array: &Bound<'_, PyAny>) -> String {
    let attribute = |name: &str| {
        array
            .getattr(name)
            .and_then(|a| a.str())
            .map(|s| s.to_string())
    };
    match (attribute("dtype"), attribute("shape")) {
        (Ok(dtype), Ok(shape)) => format!("dtype {dtype} with shape {shape}"),
        _ => format!(
            "a {}",
            array
                .get_type()
                .name()
                .map_or_else(|_| "value".to_string(), |n| n.to_string())
        ),
    }
}
