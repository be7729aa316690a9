//! Shape interpolation through a morphable model's latent space (the interpolation experiment
//! of thesis ch. 3.3.5, Figure 3.9, applied to shapes): encode two registered shapes, walk the
//! straight line between their codes, decode.

use crate::count_bounds::MAX_DECODED_SHAPES;
use crate::handy::morphable_model::MorphableModel;
use crate::handy::shape_batches::{decode_latents, encode_shapes};
use crate::{Error, Result};

/// `steps` shapes (`#V×3` each) decoded from `(1 − t) z_a + t z_b`, `t = i / (steps − 1)`,
/// with `z_a, z_b` the codes of `a, b: #V×3` (registered to the model's template). The first
/// and last are the model's reconstructions of `a` and `b`. `steps` must be in
/// `2..=`[`MAX_DECODED_SHAPES`], checked before anything is decoded.
///
/// ```
/// use meshgnn_geometry::icosphere;
/// use meshgnn_models::{Pca, interpolate_shapes};
/// let t = icosphere(0);
/// let scaled = |k: f32| t.vertices().iter().map(|p| p.map(|c| c * k)).collect::<Vec<_>>();
/// let pca = Pca::fit(&t, &[scaled(1.0), scaled(3.0)], 1)?;
/// let path = interpolate_shapes(&pca, &scaled(1.0), &scaled(3.0), 3)?;
/// assert!((path[1][0][0] - 2.0 * t.vertices()[0][0]).abs() < 1e-5); // the midpoint
/// # Ok::<(), meshgnn_models::Error>(())
/// ```
pub fn interpolate_shapes<M: MorphableModel + ?Sized>(
    model: &M,
    a: &[[f32; 3]],
    b: &[[f32; 3]],
    steps: usize,
) -> Result<Vec<Vec<[f32; 3]>>> {
    if !(2..=MAX_DECODED_SHAPES).contains(&steps) {
        return Err(Error::Invalid {
            what: "interpolation steps".into(),
            reason: format!(
                "{steps}: need 2 (both ends) to {MAX_DECODED_SHAPES} (every step is a decoded mesh)"
            ),
        });
    }
    let codes = encode_shapes(model, &[a.to_vec(), b.to_vec()])?;
    let (za, zb) = match codes.as_slice() {
        [za, zb] => (za, zb),
        _ => {
            return Err(Error::Invalid {
                what: "model".into(),
                reason: "encode returned the wrong number of codes".into(),
            });
        }
    };
    let path: Vec<Vec<f32>> = (0..steps)
        .map(|i| {
            let t = i as f64 / (steps - 1) as f64;
            za.iter()
                .zip(zb)
                .map(|(&x, &y)| ((1.0 - t) * f64::from(x) + t * f64::from(y)) as f32)
                .collect()
        })
        .collect();
    decode_latents(model, &path)
}
