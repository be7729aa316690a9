//! Batched encoding and decoding of plain vertex arrays through any [`MorphableModel`], the
//! bridge between datasets (`Vec<[f32; 3]>` per shape) and the models' `(B, V, 3)` tensors.

use candle_core::{Device, Tensor};

use crate::handy::morphable_model::MorphableModel;
use crate::tensor_file::{flatten_points, unflatten_points};
use crate::{Error, Result};

/// Shapes per forward pass: bounds memory for large templates.
pub const BATCH_SHAPES: usize = 32;

/// Encodes `shapes` (`S` shapes, each `#V×3`, on the model's template) into `S × Z` codes, in
/// batches of [`BATCH_SHAPES`] on the CPU.
///
/// ```
/// use meshgnn_geometry::icosphere;
/// use meshgnn_models::{Pca, decode_latents, encode_shapes};
/// let t = icosphere(0);
/// let shapes: Vec<Vec<[f32; 3]>> = (0..3)
///     .map(|i| t.vertices().iter().map(|p| p.map(|c| c * (1.0 + i as f32))).collect())
///     .collect();
/// let pca = Pca::fit(&t, &shapes, 1)?;
/// let z = encode_shapes(&pca, &shapes)?;
/// let back = decode_latents(&pca, &z)?;
/// assert!((back[2][0][0] - shapes[2][0][0]).abs() < 1e-5);
/// # Ok::<(), meshgnn_models::Error>(())
/// ```
pub fn encode_shapes<M: MorphableModel + ?Sized>(
    model: &M,
    shapes: &[Vec<[f32; 3]>],
) -> Result<Vec<Vec<f32>>> {
    let v = model.template().vertex_count();
    if let Some(i) = shapes.iter().position(|s| s.len() != v) {
        return Err(Error::Invalid {
            what: format!("shape {i}"),
            reason: format!(
                "{} vertices, the model's template has {v}",
                shapes.get(i).map_or(0, Vec::len)
            ),
        });
    }
    let mut out = Vec::with_capacity(shapes.len());
    for chunk in shapes.chunks(BATCH_SHAPES) {
        let flat: Vec<f32> = chunk.iter().flat_map(|s| flatten_points(s)).collect();
        let x = Tensor::from_vec(flat, (chunk.len(), v, 3), &Device::Cpu)?;
        let z = model
            .encode(&x)?
            .to_dtype(candle_core::DType::F32)?
            .to_vec2::<f32>()?;
        out.extend(z);
    }
    Ok(out)
}

/// Decodes `latents` (`N × Z`) into `N` shapes `#V×3`, in batches of [`BATCH_SHAPES`].
pub fn decode_latents<M: MorphableModel + ?Sized>(
    model: &M,
    latents: &[Vec<f32>],
) -> Result<Vec<Vec<[f32; 3]>>> {
    let z = model.latent_size();
    if let Some(i) = latents.iter().position(|l| l.len() != z) {
        return Err(Error::Invalid {
            what: format!("latent {i}"),
            reason: format!("the model's latent size is {z}"),
        });
    }
    let mut out = Vec::with_capacity(latents.len());
    for chunk in latents.chunks(BATCH_SHAPES) {
        let flat: Vec<f32> = chunk.iter().flatten().copied().collect();
        let t = Tensor::from_vec(flat, (chunk.len(), z), &Device::Cpu)?;
        let x = model.decode(&t)?.to_dtype(candle_core::DType::F32)?;
        let b = chunk.len();
        let flat: Vec<f32> = x.flatten_all()?.to_vec1()?;
        let per = flat.len() / b.max(1);
        out.extend(flat.chunks_exact(per.max(1)).map(unflatten_points));
    }
    Ok(out)
}

/// Encode + decode of every shape: the model's reconstructions (`S` shapes `#V×3`).
pub fn reconstruct_shapes<M: MorphableModel + ?Sized>(
    model: &M,
    shapes: &[Vec<[f32; 3]>],
) -> Result<Vec<Vec<[f32; 3]>>> {
    decode_latents(model, &encode_shapes(model, shapes)?)
}
