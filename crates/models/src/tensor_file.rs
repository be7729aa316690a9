//! Plain arrays in and out of safetensors buffers (the checkpoint format of the PCA model
//! and of the `handy` latent statistics), without going through candle.

use std::collections::HashMap;
use std::path::Path;

use safetensors::tensor::{Dtype, SafeTensors, TensorView};

use crate::{Error, Result};

/// One named array ready to be written: dtype, shape and little-endian bytes.
pub(crate) struct Array {
    name: String,
    dtype: Dtype,
    shape: Vec<usize>,
    bytes: Vec<u8>,
}

impl Array {
    /// An `f32` array of `shape` (row-major `values`).
    pub(crate) fn f32(name: &str, shape: Vec<usize>, values: &[f32]) -> Self {
        Self {
            name: name.to_string(),
            dtype: Dtype::F32,
            shape,
            bytes: values.iter().flat_map(|v| v.to_le_bytes()).collect(),
        }
    }

    /// An `f64` array of `shape`.
    pub(crate) fn f64(name: &str, shape: Vec<usize>, values: &[f64]) -> Self {
        Self {
            name: name.to_string(),
            dtype: Dtype::F64,
            shape,
            bytes: values.iter().flat_map(|v| v.to_le_bytes()).collect(),
        }
    }

    /// A `u32` array of `shape`.
    pub(crate) fn u32(name: &str, shape: Vec<usize>, values: &[u32]) -> Self {
        Self {
            name: name.to_string(),
            dtype: Dtype::U32,
            shape,
            bytes: values.iter().flat_map(|v| v.to_le_bytes()).collect(),
        }
    }
}

fn checkpoint_error(source: &Path, reason: impl Into<String>) -> Error {
    Error::Checkpoint {
        path: source.to_path_buf(),
        reason: reason.into(),
    }
}

/// Serialises `arrays` with `metadata` into a safetensors buffer.
pub(crate) fn serialize_arrays(
    arrays: &[Array],
    metadata: HashMap<String, String>,
    source: &Path,
) -> Result<Vec<u8>> {
    let views = arrays
        .iter()
        .map(|a| {
            TensorView::new(a.dtype, a.shape.clone(), &a.bytes)
                .map(|v| (a.name.clone(), v))
                .map_err(|e| checkpoint_error(source, format!("array {}: {e}", a.name)))
        })
        .collect::<Result<Vec<_>>>()?;
    safetensors::serialize(views, Some(metadata))
        .map_err(|e| checkpoint_error(source, format!("cannot serialise: {e}")))
}

/// Parses a safetensors buffer.
pub(crate) fn parse<'a>(bytes: &'a [u8], source: &Path) -> Result<SafeTensors<'a>> {
    SafeTensors::deserialize(bytes)
        .map_err(|e| checkpoint_error(source, format!("not a safetensors file: {e}")))
}

fn view<'a>(
    st: &'a SafeTensors<'a>,
    name: &str,
    dtype: Dtype,
    source: &Path,
) -> Result<TensorView<'a>> {
    let v = st
        .tensor(name)
        .map_err(|_| checkpoint_error(source, format!("missing array {name}")))?;
    if v.dtype() != dtype {
        return Err(checkpoint_error(
            source,
            format!("array {name} is {:?}, expected {dtype:?}", v.dtype()),
        ));
    }
    Ok(v)
}

/// Reads the `f32` array `name`: (shape, values).
pub(crate) fn read_f32(
    st: &SafeTensors<'_>,
    name: &str,
    source: &Path,
) -> Result<(Vec<usize>, Vec<f32>)> {
    let v = view(st, name, Dtype::F32, source)?;
    let values = v
        .data()
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    Ok((v.shape().to_vec(), values))
}

/// Reads the `f64` array `name`: (shape, values).
pub(crate) fn read_f64(
    st: &SafeTensors<'_>,
    name: &str,
    source: &Path,
) -> Result<(Vec<usize>, Vec<f64>)> {
    let v = view(st, name, Dtype::F64, source)?;
    let values = v
        .data()
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]))
        .collect();
    Ok((v.shape().to_vec(), values))
}

/// Reads the `u32` array `name`: (shape, values).
pub(crate) fn read_u32(
    st: &SafeTensors<'_>,
    name: &str,
    source: &Path,
) -> Result<(Vec<usize>, Vec<u32>)> {
    let v = view(st, name, Dtype::U32, source)?;
    let values = v
        .data()
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    Ok((v.shape().to_vec(), values))
}

/// Checks that an array read from a checkpoint has `expected` shape.
pub(crate) fn check_shape(
    name: &str,
    shape: &[usize],
    expected: &[usize],
    source: &Path,
) -> Result<()> {
    if shape != expected {
        return Err(checkpoint_error(
            source,
            format!("array {name} has shape {shape:?}, expected {expected:?}"),
        ));
    }
    Ok(())
}

/// Packs `vertices: #V×3` as a flat row-major vector.
pub(crate) fn flatten_points(points: &[[f32; 3]]) -> Vec<f32> {
    points.iter().flatten().copied().collect()
}

/// Unpacks a flat row-major vector into `#V×3` points (a trailing partial row is dropped).
pub(crate) fn unflatten_points(flat: &[f32]) -> Vec<[f32; 3]> {
    flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arrays_round_trip() {
        let src = Path::new("mem");
        let arrays = [
            Array::f32("a", vec![2, 2], &[1.0, 2.0, 3.0, -4.5]),
            Array::f64("b", vec![1], &[0.25]),
            Array::u32("c", vec![3], &[7, 8, 9]),
        ];
        let meta: HashMap<String, String> = [("k".to_string(), "v".to_string())].into();
        let bytes = serialize_arrays(&arrays, meta, src).unwrap();
        let st = parse(&bytes, src).unwrap();
        assert_eq!(
            read_f32(&st, "a", src).unwrap(),
            (vec![2, 2], vec![1.0, 2.0, 3.0, -4.5])
        );
        assert_eq!(read_f64(&st, "b", src).unwrap().1, vec![0.25]);
        assert_eq!(read_u32(&st, "c", src).unwrap().1, vec![7, 8, 9]);
        assert!(read_f32(&st, "b", src).is_err());
        assert!(
            read_f32(&st, "zz", src)
                .unwrap_err()
                .to_string()
                .contains("zz")
        );
        let (_, header) = SafeTensors::read_metadata(&bytes).unwrap();
        assert_eq!(
            header
                .metadata()
                .as_ref()
                .and_then(|m| m.get("k"))
                .map(String::as_str),
            Some("v")
        );
    }
}
