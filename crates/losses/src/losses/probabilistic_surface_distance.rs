//! Probabilistic surface distance, forward (thesis eq. 6.9) and reverse (eq. 6.10) terms.
//!
//! # Definition choices
//! - The generated surface is `vertices: (V, 3)` with candidate `faces: #F×3` and face
//!   probabilities `(F)`; barycentres and samples are linear in the vertices, so both terms
//!   are differentiable in positions and probabilities.
//! - Eq. 6.10's samples `y` are the centroids of the `n²` sub-triangles of each face
//!   ([`crate::predicates::triangle_lattice`], `n = 3` by default): deterministic and uniform;
//!   `p_y` is the probability of the face `y` lies on.
//! - "Its k-nearest triangles apart from its own" are the `k` faces (default 3) whose
//!   barycentres are nearest to `y`, excluding `y`'s face; `x_{t_k}` is that face's barycentre.
//! - Sums are divided by the number of barycentres / samples, like the other losses.

use crate::losses::tensor_points::{
    check_vector, index_tensor, nearest_index_tensor, points_of, row_squared_distances,
};
use crate::point_index::PointIndex;
use crate::predicates::{barycentric_point, triangle_lattice};
use crate::validate::check_faces;
use crate::{Error, Result};
use candle_core::{DType, Tensor};

/// Barycentres `(F, 3)` of `faces` over `vertices: (V, 3)`, differentiable in the vertices.
fn barycentres(vertices: &Tensor, faces: &[[u32; 3]]) -> Result<Tensor> {
    let device = vertices.device();
    let mut sum: Option<Tensor> = None;
    for corner in 0..3 {
        let idx = index_tensor(faces.iter().map(|f| f[corner]).collect(), device)?;
        let v = vertices.index_select(&idx, 0)?;
        sum = Some(match sum {
            Some(s) => s.add(&v)?,
            None => v,
        });
    }
    let sum = sum.ok_or(Error::Empty { what: "faces" })?;
    Ok(sum.affine(1.0 / 3.0, 0.0)?)
}

/// Shared input checks; returns the detached vertex positions.
fn check_surface(vertices: &Tensor, faces: &[[u32; 3]], probs: &Tensor) -> Result<Vec<[f32; 3]>> {
    let v = points_of("generated vertices", vertices)?;
    if faces.is_empty() {
        return Err(Error::Empty {
            what: "generated faces",
        });
    }
    check_faces("generated faces", faces, v.len())?;
    check_vector("face probabilities", probs, faces.len())?;
    Ok(v)
}

/// Eq. 6.9: `mean_{b̂} p_b̂ min_{b∈B} ‖b̂ − b‖²` over the barycentres `b̂` of the generated
/// `faces` on `vertices: (V, 3)` with probabilities `face_probs: (F)`, against the barycentres
/// `target_barycentres: (B, 3)` of the original mesh.
///
/// ```
/// use candle_core::{Device, Tensor};
/// use meshgnn_losses::losses::probabilistic_surface_forward;
/// let d = Device::Cpu;
/// let v = Tensor::new(&[[0.0f32, 0.0, 0.0], [3.0, 0.0, 0.0], [0.0, 3.0, 0.0]], &d)?;
/// let target = Tensor::new(&[[1.0f32, 1.0, 2.0]], &d)?; // 2 above the barycentre (1, 1, 0)
/// let p = Tensor::new(&[0.25f32], &d)?;
/// let l = probabilistic_surface_forward(&v, &[[0, 1, 2]], &p, &target)?;
/// assert_eq!(l.to_scalar::<f32>()?, 1.0); // 0.25 · 4
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn probabilistic_surface_forward(
    vertices: &Tensor,
    faces: &[[u32; 3]],
    face_probs: &Tensor,
    target_barycentres: &Tensor,
) -> Result<Tensor> {
    check_surface(vertices, faces, face_probs)?;
    let target = points_of("target barycentres", target_barycentres)?;
    let b = barycentres(vertices, faces)?;
    let bp = points_of("generated barycentres", &b)?;
    let nn = nearest_index_tensor(&bp, &target, vertices.device())?;
    Ok(
        row_squared_distances(&b, &target_barycentres.index_select(&nn, 0)?)?
            .mul(face_probs)?
            .mean_all()?,
    )
}

/// Parameters of the reverse term (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReverseSurfaceParams {
    /// Number of nearest other faces `k` averaged in the second term of eq. 6.10.
    pub neighbours: usize,
    /// Lattice subdivision `n`: `n²` samples per face.
    pub samples_per_side: usize,
}

impl Default for ReverseSurfaceParams {
    fn default() -> Self {
        Self {
            neighbours: 3,
            samples_per_side: 3,
        }
    }
}

/// Eq. 6.10: `mean_y [ p_y min_{x∈P} ‖x − y‖² + (1 − p_y) (1/k) Σ_k p_{t_k} ‖x_{t_k} − y‖² ]`
/// over samples `y` on the generated `faces` of `vertices: (V, 3)` with `face_probs: (F)`,
/// against points `target: (N, 3)` of the original surface. The second term is the cost of
/// dropping `y`'s face: `y` must then be covered by the neighbouring faces `t_k`. A single
/// face has no neighbours and its second term is 0.
///
/// ```
/// use candle_core::{Device, Tensor};
/// use meshgnn_losses::losses::{probabilistic_surface_reverse, ReverseSurfaceParams};
/// let d = Device::Cpu;
/// let v = Tensor::new(&[[0.0f32, 0.0, 0.0], [3.0, 0.0, 0.0], [0.0, 3.0, 0.0]], &d)?;
/// let p = Tensor::new(&[1.0f32], &d)?;
/// let params = ReverseSurfaceParams { neighbours: 3, samples_per_side: 1 };
/// let target = Tensor::new(&[[1.0f32, 1.0, 0.5]], &d)?; // 0.5 above the only sample
/// let l = probabilistic_surface_reverse(&v, &[[0, 1, 2]], &p, &target, params)?;
/// assert_eq!(l.to_scalar::<f32>()?, 0.25);
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn probabilistic_surface_reverse(
    vertices: &Tensor,
    faces: &[[u32; 3]],
    face_probs: &Tensor,
    target: &Tensor,
    params: ReverseSurfaceParams,
) -> Result<Tensor> {
    let v = check_surface(vertices, faces, face_probs)?;
    let target_points = points_of("target points", target)?;
    if params.samples_per_side == 0 {
        return Err(Error::InvalidParameter {
            name: "samples_per_side",
            message: "at least one sample per face is needed".into(),
        });
    }
    let device = vertices.device();
    let dtype = vertices.dtype();
    let lattice = triangle_lattice(params.samples_per_side);
    let per_face = lattice.len();
    let count = faces.len() * per_face;

    // Samples y = Σ_c w_c v_{f,c}, built as three gathers scaled by per-sample weights.
    let mut y: Option<Tensor> = None;
    for corner in 0..3 {
        let idx: Vec<u32> = faces
            .iter()
            .flat_map(|f| std::iter::repeat_n(f[corner], per_face))
            .collect();
        let w: Vec<f32> = (0..faces.len())
            .flat_map(|_| lattice.iter().map(move |b| b[corner]))
            .collect();
        let w = Tensor::from_vec(w, (count, 1), device)?.to_dtype(dtype)?;
        let part = vertices
            .index_select(&index_tensor(idx, device)?, 0)?
            .broadcast_mul(&w)?;
        y = Some(match y {
            Some(s) => s.add(&part)?,
            None => part,
        });
    }
    let y = y.ok_or(Error::Empty { what: "faces" })?;
    let face_of_sample = index_tensor(
        (0..faces.len() as u32)
            .flat_map(|f| std::iter::repeat_n(f, per_face))
            .collect(),
        device,
    )?;
    let p_y = face_probs.index_select(&face_of_sample, 0)?;

    // First term: p_y · distance to the nearest original point.
    let y_points: Vec<[f32; 3]> = faces
        .iter()
        .flat_map(|f| {
            let t = f.map(|i| v.get(i as usize).copied().unwrap_or([0.0; 3]));
            lattice.iter().map(move |w| barycentric_point(&t, w))
        })
        .collect();
    let nn = nearest_index_tensor(&y_points, &target_points, device)?;
    let first = row_squared_distances(&y, &target.index_select(&nn, 0)?)?.mul(&p_y)?;

    // Second term: (1 − p_y) · mean over the k nearest other faces of p_t ‖b_t − y‖².
    let k = params.neighbours.min(faces.len() - 1);
    if k == 0 {
        return Ok(first.mean_all()?);
    }
    let b = barycentres(vertices, faces)?;
    let b_points = points_of("generated barycentres", &b)?;
    let tree = PointIndex::new(&b_points);
    let mut neighbour = Vec::with_capacity(count * k);
    let mut owner = Vec::with_capacity(count * k);
    for (s, q) in y_points.iter().enumerate() {
        let own = s / per_face;
        let found = tree.nearest_k(q, k + 1);
        let others = found.iter().filter(|(f, _)| *f != own).take(k);
        for &(f, _) in others {
            neighbour.push(f as u32);
            owner.push(s as u32);
        }
    }
    let neighbour = index_tensor(neighbour, device)?;
    let owner = index_tensor(owner, device)?;
    let near = row_squared_distances(&b.index_select(&neighbour, 0)?, &y.index_select(&owner, 0)?)?
        .mul(&face_probs.index_select(&neighbour, 0)?)?;
    // Average the k contributions of each sample: scatter by summing into (count) via a
    // reshape, since every sample received exactly k neighbours (F − 1 ≥ k others exist).
    let near = near
        .reshape((count, k))?
        .sum(1)?
        .affine(1.0 / k as f64, 0.0)?;
    let ones = Tensor::ones(count, DType::F32, device)?.to_dtype(p_y.dtype())?;
    let second = ones.sub(&p_y)?.mul(&near)?;
    Ok(first.add(&second)?.mean_all()?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::losses::gradient_check::assert_gradient_matches;
    use candle_core::Device;

    fn quad() -> (Tensor, Vec<[u32; 3]>) {
        let v = Tensor::new(
            &[
                [0.0f64, 0.0, 0.0],
                [1.0, 0.0, 0.1],
                [0.0, 1.0, -0.1],
                [1.0, 1.0, 0.3],
            ],
            &Device::Cpu,
        )
        .unwrap();
        (v, vec![[0, 1, 2], [1, 3, 2], [0, 3, 1]])
    }

    #[test]
    fn forward_gradients() {
        let (v, f) = quad();
        let dev = Device::Cpu;
        let target = Tensor::new(&[[0.2f64, 0.3, 0.5], [0.9, 0.6, -0.4]], &dev).unwrap();
        let p = Tensor::new(&[0.2f64, 0.7, 0.5], &dev).unwrap();
        assert_gradient_matches(
            &p,
            |p| probabilistic_surface_forward(&v, &f, p, &target),
            1e-6,
        );
        assert_gradient_matches(
            &v,
            |v| probabilistic_surface_forward(v, &f, &p, &target),
            1e-6,
        );
    }

    #[test]
    fn reverse_gradients() {
        let (v, f) = quad();
        let dev = Device::Cpu;
        let target = Tensor::new(
            &[[0.2f64, 0.3, 0.5], [0.9, 0.6, -0.4], [0.1, 0.8, 0.0]],
            &dev,
        )
        .unwrap();
        let p = Tensor::new(&[0.2f64, 0.7, 0.5], &dev).unwrap();
        let params = ReverseSurfaceParams {
            neighbours: 2,
            samples_per_side: 2,
        };
        assert_gradient_matches(
            &p,
            |p| probabilistic_surface_reverse(&v, &f, p, &target, params),
            1e-6,
        );
        assert_gradient_matches(
            &v,
            |v| probabilistic_surface_reverse(v, &f, &p, &target, params),
            1e-6,
        );
    }

    #[test]
    fn reverse_hand_computed_two_faces() {
        // Two faces, one sample each (their centroids), k = 1: each sample's other face is the
        // other one. Face 0 centroid c0, face 1 centroid c1; target = {c0}.
        let dev = Device::Cpu;
        let v = Tensor::new(
            &[
                [0.0f32, 0.0, 0.0],
                [3.0, 0.0, 0.0],
                [0.0, 3.0, 0.0],
                [3.0, 3.0, 0.0],
            ],
            &dev,
        )
        .unwrap();
        let faces = [[0, 1, 2], [1, 3, 2]];
        let c0 = [1.0f32, 1.0, 0.0];
        let c1 = [2.0f32, 2.0, 0.0];
        let target = Tensor::new(&[c0], &dev).unwrap();
        let p = Tensor::new(&[0.5f32, 0.25], &dev).unwrap();
        let params = ReverseSurfaceParams {
            neighbours: 1,
            samples_per_side: 1,
        };
        let l = probabilistic_surface_reverse(&v, &faces, &p, &target, params)
            .unwrap()
            .to_scalar::<f32>()
            .unwrap();
        let d2 = ((c1[0] - c0[0]).powi(2) + (c1[1] - c0[1]).powi(2)) as f64; // 2
        // y0 = c0: 0.5·0 + 0.5·(0.25·2) ; y1 = c1: 0.25·2 + 0.75·(0.5·2)
        let expected = (0.5 * 0.25 * d2 + 0.25 * d2 + 0.75 * 0.5 * d2) / 2.0;
        assert!((f64::from(l) - expected).abs() < 1e-6, "{l} vs {expected}");
    }
}
