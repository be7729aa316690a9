//! Intrinsic evaluation of a morphable model (thesis ch. 3.4.1, Figure 3.10, Table 3.2):
//! generalisation to held-out shapes and specificity of random samples, for any
//! [`MorphableModel`] — the spiral autoencoder and the PCA baseline alike. The metrics
//! themselves are `meshgnn_losses::metrics::{generalisation, specificity}`.

use meshgnn_losses::metrics::{ErrorSummary, generalisation, specificity};

use crate::handy::latent_gaussian::LatentGaussian;
use crate::handy::morphable_model::MorphableModel;
use crate::handy::shape_batches::{decode_latents, encode_shapes};
use crate::tensor_file::flatten_points;
use crate::{Error, Result};

/// Samples of the thesis' specificity experiment.
pub const SPECIFICITY_SAMPLES: usize = 1000;

/// Generalisation (Table 3.2): mean per-vertex error between each of `shapes` (`S` shapes
/// `#V×3`, not seen in training) and its reconstruction `decode(encode(x))`, in input units
/// (mm for hands); mean and standard deviation over shapes.
///
/// ```
/// use meshgnn_geometry::icosphere;
/// use meshgnn_models::{Pca, generalisation_error};
/// let t = icosphere(0);
/// let scaled = |k: f32| t.vertices().iter().map(|p| p.map(|c| c * k)).collect::<Vec<_>>();
/// let pca = Pca::fit(&t, &[scaled(1.0), scaled(2.0)], 1)?;
/// // a shape on the model's line is reproduced exactly
/// assert!(generalisation_error(&pca, &[scaled(3.0)])?.mean < 1e-5);
/// # Ok::<(), meshgnn_models::Error>(())
/// ```
pub fn generalisation_error<M: MorphableModel + Sync + ?Sized>(
    model: &M,
    shapes: &[Vec<[f32; 3]>],
) -> Result<ErrorSummary> {
    Ok(generalisation(shapes, |s| {
        let z = encode_shapes(model, &[s.to_vec()]).map_err(to_losses)?;
        decode_latents(model, &z)
            .map_err(to_losses)?
            .into_iter()
            .next()
            .ok_or(meshgnn_losses::Error::Empty {
                what: "reconstruction",
            })
    })?)
}

/// Carries a model error through the metric's callback.
fn to_losses(e: Error) -> meshgnn_losses::Error {
    meshgnn_losses::Error::InvalidParameter {
        name: "model",
        message: e.to_string(),
    }
}

/// The Gaussian over the codes of `shapes` (`S` shapes `#V×3`, `S ≥ 2`) under `model`.
pub fn latent_gaussian<M: MorphableModel + ?Sized>(
    model: &M,
    shapes: &[Vec<[f32; 3]>],
) -> Result<LatentGaussian> {
    LatentGaussian::fit(&encode_shapes(model, shapes)?)
}

/// Specificity (ch. 3.4.1, Figure 3.10 right): decodes `samples` codes drawn (with `seed`)
/// from `gaussian` and measures each one's per-vertex error to its closest shape of
/// `training` (`S` shapes `#V×3`, the model's own training set as in the thesis); input units.
///
/// ```
/// use meshgnn_geometry::icosphere;
/// use meshgnn_models::{LatentGaussian, Pca, specificity_error};
/// let t = icosphere(0);
/// let scaled = |k: f32| t.vertices().iter().map(|p| p.map(|c| c * k)).collect::<Vec<_>>();
/// let train = vec![scaled(1.0), scaled(1.0), scaled(3.0)];
/// let pca = Pca::fit(&t, &train, 1)?;
/// // a Gaussian of zero width at the first shape's code: every sample is that shape
/// let z = pca.project(&train[0])?;
/// let g = LatentGaussian::from_parts(vec![f64::from(z[0])], vec![1e-9])?;
/// let s = specificity_error(&pca, &train, &g, 10, 0)?;
/// assert!(s.mean < 1e-4);
/// # Ok::<(), meshgnn_models::Error>(())
/// ```
pub fn specificity_error<M: MorphableModel + ?Sized>(
    model: &M,
    training: &[Vec<[f32; 3]>],
    gaussian: &LatentGaussian,
    samples: usize,
    seed: u64,
) -> Result<ErrorSummary> {
    if gaussian.latent_size() != model.latent_size() {
        return Err(Error::Invalid {
            what: "latent Gaussian".into(),
            reason: format!(
                "size {}, the model's latent size is {}",
                gaussian.latent_size(),
                model.latent_size()
            ),
        });
    }
    let generated = decode_latents(model, &gaussian.sample(samples, seed))?;
    Ok(specificity(&generated, training)?)
}

/// Root-mean-square distance of `shape: #V×3` from its centroid: the scale used to make
/// fitting and specificity figures comparable.
pub(crate) fn rms_radius(shape: &[[f32; 3]]) -> f64 {
    let flat = flatten_points(shape);
    let n = (flat.len() / 3).max(1) as f64;
    let c: Vec<f64> = (0..3)
        .map(|k| {
            flat.iter()
                .skip(k)
                .step_by(3)
                .map(|&x| f64::from(x))
                .sum::<f64>()
                / n
        })
        .collect();
    (shape
        .iter()
        .map(|p| {
            (0..3)
                .map(|k| (f64::from(p[k]) - c[k]).powi(2))
                .sum::<f64>()
        })
        .sum::<f64>()
        / n)
        .sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::handy::pca::Pca;
    use meshgnn_geometry::TriMesh;

    fn tri() -> TriMesh {
        TriMesh::new(
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![[0, 1, 2]],
        )
        .unwrap()
    }

    /// shape with the first vertex moved to (x, y, 0)
    fn moved(x: f32, y: f32) -> Vec<[f32; 3]> {
        vec![[x, y, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    }

    #[test]
    fn generalisation_hand_computed() {
        // training varies only x of vertex 0; a test shape moved by y = 3 keeps an error of
        // 3 on one vertex of three: per-vertex error 1 exactly.
        let pca = Pca::fit(&tri(), &[moved(0.0, 0.0), moved(2.0, 0.0)], 1).unwrap();
        let g = generalisation_error(&pca, &[moved(5.0, 3.0), moved(1.0, 0.0)]).unwrap();
        assert!((g.mean - 0.5).abs() < 1e-6, "{g:?}"); // (1 + 0) / 2
        assert!((g.std - 0.5).abs() < 1e-6);
    }

    #[test]
    fn specificity_hand_computed() {
        // model line x ∈ ℝ for vertex 0; training shapes at x = 0 and x = 10; a degenerate
        // Gaussian at x = 4 gives samples 4 away from the closest (x = 0): error 4/3.
        let train = vec![moved(0.0, 0.0), moved(10.0, 0.0)];
        let pca = Pca::fit(&tri(), &train, 1).unwrap();
        let z = pca.project(&moved(4.0, 0.0)).unwrap();
        let g = LatentGaussian::from_parts(vec![f64::from(z[0])], vec![1e-12]).unwrap();
        let s = specificity_error(&pca, &train, &g, 5, 3).unwrap();
        assert!((s.mean - 4.0 / 3.0).abs() < 1e-5, "{s:?}");
        // latent size mismatch is refused
        let g2 = LatentGaussian::standard(2);
        assert!(specificity_error(&pca, &train, &g2, 5, 3).is_err());
        // the fitted Gaussian of the training codes is standard for a whitened PCA
        let fitted = latent_gaussian(&pca, &train).unwrap();
        assert!((fitted.std()[0] - 1.0).abs() < 1e-5);
        assert!(fitted.mean()[0].abs() < 1e-5);
    }

    #[test]
    fn rms_radius_of_a_square() {
        let s = [
            [1.0, 1.0, 0.0],
            [-1.0, 1.0, 0.0],
            [1.0, -1.0, 0.0],
            [-1.0, -1.0, 0.0],
        ];
        assert!((rms_radius(&s) - 2f64.sqrt()).abs() < 1e-12);
    }
}
