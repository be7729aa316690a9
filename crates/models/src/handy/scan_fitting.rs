//! Fitting a morphable model to a point cloud (thesis ch. 3.4.4, Table 3.5): a latent code and
//! a similarity transform are optimised with Adam to minimise the Chamfer distance (eq. 5.6)
//! between the decoded, transformed template vertices and the scan. Following LISA (Corona et
//! al. 2022, CVPR), the fit is evaluated with R2S and S2R ([`crate::handy::scan_distances`]).
//!
//! # Conventions
//! - Model space → scan space: `y = s R (x − c) + t`, `c` the centroid of the model's mean
//!   shape, `R` from a quaternion (any non-zero 4-vector, normalised inside the formula, so
//!   the gradient is smooth everywhere), `s = s₀ exp(σ)`, `t = t₀ + r₀ τ`: every optimised
//!   number (`z`, `q`, `σ`, `τ`) is dimensionless, so one Adam learning rate fits them all.
//! - Initialisation: the mean code (zero, or the prior's mean) and the prior's modes, each
//!   probed (see [`fit_scan`]); identity rotation (or the global start's); `t₀` the scan's
//!   centroid; `s₀` the ratio of the scan's and the start shape's RMS radii (or 1).
//! - Loss: Chamfer (mean of squared nearest-vertex distances) divided by `r₀²` (`r₀` the RMS
//!   radius of the mean shape times `s₀`), plus `prior_weight · ‖L⁻¹ (z − μ)‖² / Z` when a
//!   latent Gaussian is given. [`ChamferDirection::ScanToModel`] keeps only the scan → model
//!   term: a partial scan (one side of a hand) says nothing about the unseen side, which the
//!   symmetric term would pull onto the visible points; the prior keeps that side plausible.
//! - Deterministic: the scan subset comes from a seeded sampler, everything else is fixed.

use candle_core::{DType, Device, Tensor, Var};
use meshgnn_geometry::{TriMesh, vertex_normals};
use meshgnn_graph::{knn_query, uniform_sampling};
use meshgnn_losses::losses::chamfer_loss;

use crate::adam::{Adam, AdamConfig};
use crate::handy::latent_gaussian::LatentGaussian;
use crate::handy::morphable_evaluation::rms_radius;
use crate::handy::morphable_model::MorphableModel;
use crate::handy::scan_distances::{ScanDistances, scan_distances};
use crate::handy::scan_orientation::starting_rotations;
use crate::handy::shape_batches::decode_latents;
use crate::tensor_file::{flatten_points, unflatten_points};
use crate::{Error, Result};

/// Which Chamfer terms drive the fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ChamferDirection {
    /// Both directions (eq. 5.6): for complete scans.
    Symmetric,
    /// Scan → model only: for partial scans (default; a complete scan fits well too).
    #[default]
    ScanToModel,
}

/// Options of [`fit_scan`]; defaults suit a hand scan in millimetres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScanFitOptions {
    /// Adam steps.
    pub steps: usize,
    /// Initial Adam learning rate; decays linearly to a tenth over the steps.
    pub learning_rate: f64,
    /// Chamfer terms used.
    pub direction: ChamferDirection,
    /// The scan is randomly subsampled to at most this many points during the optimisation.
    pub max_scan_points: usize,
    /// Weight of the Mahalanobis latent prior (used when a prior is passed).
    pub prior_weight: f64,
    /// Optimise the scale (else it stays at its initial value).
    pub fit_scale: bool,
    /// Initialise the scale from the RMS radii (else 1: model and scan in the same units).
    pub estimate_scale: bool,
    /// Seed of the scan subsampling.
    pub seed: u64,
    /// Direction from the object to a single-view scanner, when known: the scan is matched
    /// only against model vertices facing it (back-face culling of the model, recomputed every
    /// step), and the initial translation aligns the scan's centroid with the centroid of the
    /// model's visible vertices. Without it a one-sided scan can settle *between* the model's
    /// front and back surfaces.
    pub view_direction: Option<[f32; 3]>,
    /// For scans in any orientation, handedness and pose (beyond the thesis, whose scans are
    /// aligned): starting codes are the prior's mean and its modes (the pose clusters of the
    /// training codes, [`LatentGaussian::modes`]); each is turned by the identity and by the
    /// four rotations that align its shape's principal axes with the scan's, on the scan and
    /// on its mirror image (a left hand for a right-hand model). Every start is probed by its
    /// loss after one step, the best four run a fifth of the steps, and the two with the
    /// lowest loss are fitted again with all of them (the lower final loss is kept).
    pub global_init: bool,
}

impl Default for ScanFitOptions {
    fn default() -> Self {
        Self {
            steps: 300,
            learning_rate: 0.02,
            direction: ChamferDirection::ScanToModel,
            max_scan_points: 4000,
            prior_weight: 1e-4,
            fit_scale: true,
            estimate_scale: false,
            seed: 0,
            view_direction: None,
            global_init: false,
        }
    }
}

/// A similarity transform `y = s R x + t`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimilarityTransform {
    /// Scale `s > 0`.
    pub scale: f64,
    /// Unit quaternion `(w, x, y, z)` of `R`.
    pub rotation: [f64; 4],
    /// Translation `t`.
    pub translation: [f64; 3],
}

impl SimilarityTransform {
    /// The identity.
    pub const IDENTITY: Self = Self {
        scale: 1.0,
        rotation: [1.0, 0.0, 0.0, 0.0],
        translation: [0.0; 3],
    };

    /// `s`, rotation by `angle` radians about `axis` (any non-zero vector), `t`.
    ///
    /// ```
    /// use meshgnn_models::SimilarityTransform;
    /// let t = SimilarityTransform::from_axis_angle(2.0, [0.0, 0.0, 1.0], std::f64::consts::FRAC_PI_2, [1.0, 0.0, 0.0]);
    /// let y = t.apply([1.0, 0.0, 0.0]);
    /// assert!((y[0] - 1.0).abs() < 1e-6 && (y[1] - 2.0).abs() < 1e-6);
    /// ```
    pub fn from_axis_angle(scale: f64, axis: [f64; 3], angle: f64, translation: [f64; 3]) -> Self {
        let n = axis.iter().map(|a| a * a).sum::<f64>().sqrt();
        let (s, c) = (0.5 * angle).sin_cos();
        let rotation = if n > 0.0 {
            [c, s * axis[0] / n, s * axis[1] / n, s * axis[2] / n]
        } else {
            [1.0, 0.0, 0.0, 0.0]
        };
        Self {
            scale,
            rotation,
            translation,
        }
    }

    /// The rotation matrix `R` (row-major) of the (normalised) quaternion.
    pub fn rotation_matrix(&self) -> [[f64; 3]; 3] {
        let [w, x, y, z] = self.rotation;
        let n = (w * w + x * x + y * y + z * z).max(f64::MIN_POSITIVE);
        [
            [
                (w * w + x * x - y * y - z * z) / n,
                2.0 * (x * y - w * z) / n,
                2.0 * (x * z + w * y) / n,
            ],
            [
                2.0 * (x * y + w * z) / n,
                (w * w - x * x + y * y - z * z) / n,
                2.0 * (y * z - w * x) / n,
            ],
            [
                2.0 * (x * z - w * y) / n,
                2.0 * (y * z + w * x) / n,
                (w * w - x * x - y * y + z * z) / n,
            ],
        ]
    }

    /// Rotation angle of `R` in radians, `[0, π]`.
    pub fn angle(&self) -> f64 {
        let [w, x, y, z] = self.rotation;
        let v = (x * x + y * y + z * z).sqrt();
        2.0 * v.atan2(w.abs())
    }

    /// `s R p + t`.
    pub fn apply(&self, p: [f32; 3]) -> [f32; 3] {
        let r = self.rotation_matrix();
        let p = p.map(f64::from);
        std::array::from_fn(|i| {
            let rp: f64 = (0..3).map(|k| r[i][k] * p[k]).sum();
            (self.scale * rp + self.translation[i]) as f32
        })
    }

    /// The composition `self ∘ other` (apply `other` first).
    pub fn compose(&self, other: &Self) -> Self {
        let [a1, b1, c1, d1] = self.rotation;
        let [a2, b2, c2, d2] = other.rotation;
        let rotation = [
            a1 * a2 - b1 * b2 - c1 * c2 - d1 * d2,
            a1 * b2 + b1 * a2 + c1 * d2 - d1 * c2,
            a1 * c2 - b1 * d2 + c1 * a2 + d1 * b2,
            a1 * d2 + b1 * c2 - c1 * b2 + d1 * a2,
        ];
        let t = other.translation.map(|c| c as f32);
        let moved = self.apply(t);
        Self {
            scale: self.scale * other.scale,
            rotation,
            translation: moved.map(f64::from),
        }
    }
}

/// The result of [`fit_scan`].
#[derive(Debug, Clone, PartialEq)]
pub struct ScanFit {
    /// Fitted vertices in scan space, `#V×3` (the template's triangles).
    pub vertices: Vec<[f32; 3]>,
    /// Fitted latent code, `Z`.
    pub latent: Vec<f32>,
    /// Model space → scan space.
    pub transform: SimilarityTransform,
    /// R2S / S2R of the fit against the whole input scan (input units).
    pub distances: ScanDistances,
    /// Final value of the (dimensionless) loss.
    pub loss: f64,
    /// Whether the scan was mirrored (`x → −x`) to match the model: `vertices` are mirrored
    /// back into the scan's frame (so the template's triangles face inwards: flip them), while
    /// `latent` and `transform` describe the fit to the mirrored scan.
    pub mirrored: bool,
}

fn invalid(what: &str, reason: impl Into<String>) -> Error {
    Error::Invalid {
        what: what.to_string(),
        reason: reason.into(),
    }
}

fn centroid(points: &[[f32; 3]]) -> [f64; 3] {
    let n = points.len().max(1) as f64;
    std::array::from_fn(|k| points.iter().map(|p| f64::from(p[k])).sum::<f64>() / n)
}

/// `R` (3, 3) of an unnormalised quaternion `q: (4)`, differentiable.
fn quaternion_matrix(q: &Tensor) -> Result<Tensor> {
    let c = |i| q.narrow(0, i, 1);
    let (w, x, y, z) = (c(0)?, c(1)?, c(2)?, c(3)?);
    let n = q.sqr()?.sum_all()?;
    let (ww, xx, yy, zz) = (w.sqr()?, x.sqr()?, y.sqr()?, z.sqr()?);
    let two = |a: &Tensor, b: &Tensor| -> candle_core::Result<Tensor> { (a * b)? * 2.0 };
    let entries = [
        ((&ww + &xx)? - &yy)?.sub(&zz)?,
        (two(&x, &y)? - two(&w, &z)?)?,
        (two(&x, &z)? + two(&w, &y)?)?,
        (two(&x, &y)? + two(&w, &z)?)?,
        ((&ww - &xx)? + &yy)?.sub(&zz)?,
        (two(&y, &z)? - two(&w, &x)?)?,
        (two(&x, &z)? - two(&w, &y)?)?,
        (two(&y, &z)? + two(&w, &x)?)?,
        ((&ww - &xx)? - &yy)?.add(&zz)?,
    ];
    Ok(Tensor::cat(&entries, 0)?
        .reshape((3, 3))?
        .broadcast_div(&n)?)
}

/// Mean over `from: (N, 3)` rows of the squared distance to the nearest row of `to: (M, 3)`;
/// the correspondence is found on the detached values, so the loss is differentiable in
/// `to` (piecewise, like the Chamfer losses).
fn directed_chamfer(
    from: &[[f32; 3]],
    from_t: &Tensor,
    to: &Tensor,
    visible: Option<(&[[u32; 3]], [f32; 3])>,
) -> Result<Tensor> {
    let to_values = unflatten_points(&to.flatten_all()?.to_vec1::<f32>()?);
    // candidate targets: all vertices, or those facing the scanner
    let candidates: Vec<u32> = match visible {
        Some((triangles, d)) => facing_vertices(&to_values, triangles, d)?,
        None => (0..to_values.len() as u32).collect(),
    };
    let points: Vec<[f32; 3]> = candidates
        .iter()
        .filter_map(|&i| to_values.get(i as usize).copied())
        .collect();
    let nn = knn_query(from, &points, 1)?;
    let indices: Vec<u32> = nn
        .indices
        .iter()
        .map(|&j| candidates.get(j as usize).copied().unwrap_or(0))
        .collect();
    let idx = Tensor::from_vec(indices, from.len(), to.device())?;
    let nearest = to.index_select(&idx, 0)?;
    Ok((from_t - nearest)?.sqr()?.sum(1)?.mean_all()?)
}

/// Indices of the vertices of (`vertices: #V×3`, `triangles: #F×3`) whose normal faces `d`
/// (all vertices when none does).
fn facing_vertices(vertices: &[[f32; 3]], triangles: &[[u32; 3]], d: [f32; 3]) -> Result<Vec<u32>> {
    let mesh = TriMesh::new(vertices.to_vec(), triangles.to_vec())?;
    let normals = vertex_normals(&mesh);
    let facing: Vec<u32> = normals
        .iter()
        .enumerate()
        .filter(|(_, n)| n[0] * d[0] + n[1] * d[1] + n[2] * d[2] > 0.0)
        .map(|(i, _)| i as u32)
        .collect();
    Ok(if facing.is_empty() {
        (0..vertices.len() as u32).collect()
    } else {
        facing
    })
}

/// Ch. 3.4.4: fits `model` to `scan: #P×3` (partial and noisy allowed) by optimising a latent
/// code and a similarity transform with Adam (see the module conventions); `prior` (the
/// Gaussian of the training codes) regularises the code. When the prior has modes (pose
/// clusters), each is a starting code too: every start is probed by its loss after one step,
/// the best four run a fifth of the steps and the best two of those are fitted with
/// all of them (with `global_init`, over rotations and the mirror image as well). Returns the
/// fitted vertices in scan space and R2S / S2R against the whole scan.
///
/// ```
/// use meshgnn_geometry::icosphere;
/// use meshgnn_models::{Pca, ScanFitOptions, fit_scan};
/// let t = icosphere(2);
/// let shapes: Vec<Vec<[f32; 3]>> = (0..3)
///     .map(|i| t.vertices().iter().map(|p| [p[0] * (1.0 + 0.3 * i as f32), p[1], p[2]]).collect())
///     .collect();
/// let pca = Pca::fit(&t, &shapes, 1)?;
/// let fit = fit_scan(&pca, &shapes[2], None, &ScanFitOptions::default())?;
/// assert!(fit.distances.s2r < 0.01);
/// # Ok::<(), meshgnn_models::Error>(())
/// ```
pub fn fit_scan<M: MorphableModel + ?Sized>(
    model: &M,
    scan: &[[f32; 3]],
    prior: Option<&LatentGaussian>,
    options: &ScanFitOptions,
) -> Result<ScanFit> {
    let mirror = |points: &[[f32; 3]]| -> Vec<[f32; 3]> {
        points.iter().map(|p| [-p[0], p[1], p[2]]).collect()
    };
    let mirrored_scan = mirror(scan);
    // The mirror image of a one-sided scan was seen from the mirrored camera.
    let mirrored_options = ScanFitOptions {
        view_direction: options.view_direction.map(|d| [-d[0], d[1], d[2]]),
        ..*options
    };
    let both_sides = [
        (false, scan, options),
        (true, &mirrored_scan[..], &mirrored_options),
    ];
    let sides = if options.global_init {
        &both_sides[..]
    } else {
        &both_sides[..1]
    };
    let modes = prior.map(LatentGaussian::modes).unwrap_or_default();
    if sides.len() == 1 && modes.is_empty() {
        let start = FitStart {
            code: mean_code(model, prior),
            rotation: IDENTITY_ROTATION,
        };
        return fit_from(model, scan, prior, options, &start);
    }
    // Probe every start by its loss after one step: the mean code and each mode of the
    // training codes (pose clusters); with the global start each is also turned onto the
    // scan (and onto its mirror image) by the four principal-axis alignments of its shape.
    let codes = std::iter::once(mean_code(model, prior))
        .chain(modes.iter().map(|m| m.iter().map(|&c| c as f32).collect()));
    let mut probes: Vec<(f64, bool, FitStart)> = Vec::new();
    for code in codes {
        let shape = decoded(model, &code)?;
        for &(mirrored, points, opts) in sides {
            let probe = ScanFitOptions { steps: 1, ..*opts };
            let rotations = if options.global_init {
                starting_rotations(&shape, points)
            } else {
                vec![IDENTITY_ROTATION]
            };
            for rotation in rotations {
                let start = FitStart {
                    code: code.clone(),
                    rotation,
                };
                let loss = fit_from(model, points, prior, &probe, &start)?.loss;
                probes.push((loss, mirrored, start));
            }
        }
    }
    probes.sort_by(|a, b| a.0.total_cmp(&b.0));
    probes.truncate(SCREENED_STARTS);
    // Screen the most promising with a fifth of the steps; fit the best few with all of them
    // and keep the lowest final loss.
    let mut screened = Vec::with_capacity(probes.len());
    for (_, mirrored, start) in probes {
        let (_, points, opts) = sides[usize::from(mirrored)];
        let screening = ScanFitOptions {
            steps: (options.steps / 5).max(1),
            ..*opts
        };
        let loss = fit_from(model, points, prior, &screening, &start)?.loss;
        screened.push((loss, mirrored, start));
    }
    screened.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut best: Option<(bool, ScanFit)> = None;
    for (_, mirrored, start) in screened.into_iter().take(FINALISTS) {
        let (_, points, opts) = sides[usize::from(mirrored)];
        let fit = fit_from(model, points, prior, opts, &start)?;
        if best.as_ref().is_none_or(|(_, b)| fit.loss < b.loss) {
            best = Some((mirrored, fit));
        }
    }
    let Some((mirrored, fit)) = best else {
        return Err(invalid("scan fit", "no starting point"));
    };
    if !mirrored {
        return Ok(fit);
    }
    Ok(ScanFit {
        vertices: mirror(&fit.vertices),
        mirrored: true,
        ..fit
    })
}

/// How many of the probed starts are screened with a fifth of the steps.
const SCREENED_STARTS: usize = 4;

/// How many of the screened starts are fitted with all the steps (the lowest final loss is
/// kept): a fist fitted upside down can lead after a fifth of the steps and lose at the end.
const FINALISTS: usize = 2;

/// The unit quaternion of the identity rotation.
const IDENTITY_ROTATION: [f64; 4] = [1.0, 0.0, 0.0, 0.0];

/// Where one fit starts: a latent code and a rotation (a unit quaternion).
#[derive(Debug, Clone)]
struct FitStart {
    code: Vec<f32>,
    rotation: [f64; 4],
}

/// The latent code the fit starts from by default: zero, or the prior's mean.
fn mean_code<M: MorphableModel + ?Sized>(model: &M, prior: Option<&LatentGaussian>) -> Vec<f32> {
    prior.map_or(vec![0.0; model.latent_size()], |p| {
        p.mean().iter().map(|&m| m as f32).collect()
    })
}

/// The shape `#V×3` the model decodes from `code`.
fn decoded<M: MorphableModel + ?Sized>(model: &M, code: &[f32]) -> Result<Vec<[f32; 3]>> {
    Ok(decode_latents(model, &[code.to_vec()])?
        .pop()
        .unwrap_or_default())
}

/// One fit from `start`; see [`fit_scan`].
fn fit_from<M: MorphableModel + ?Sized>(
    model: &M,
    scan: &[[f32; 3]],
    prior: Option<&LatentGaussian>,
    options: &ScanFitOptions,
    start: &FitStart,
) -> Result<ScanFit> {
    if scan.len() < 3 {
        return Err(invalid(
            "scan",
            format!("needs at least 3 points, got {}", scan.len()),
        ));
    }
    if let Some(i) = scan.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
        return Err(invalid(&format!("scan point {i}"), "non-finite coordinate"));
    }
    if options.steps == 0
        || options.learning_rate.is_nan()
        || options.learning_rate <= 0.0
        || options.max_scan_points < 3
    {
        return Err(invalid(
            "scan fit options",
            "steps ≥ 1, learning rate > 0 and max_scan_points ≥ 3 are required",
        ));
    }
    let z_size = model.latent_size();
    if let Some(p) = prior
        && p.latent_size() != z_size
    {
        return Err(invalid(
            "latent prior",
            format!(
                "size {}, the model's latent size is {z_size}",
                p.latent_size()
            ),
        ));
    }
    if start.code.len() != z_size {
        return Err(invalid(
            "starting code",
            format!(
                "size {}, the model's latent size is {z_size}",
                start.code.len()
            ),
        ));
    }
    let dev = Device::Cpu;
    let start_shape = decoded(model, &start.code)?;
    let c = centroid(&start_shape);
    let model_radius = rms_radius(&start_shape);
    let scan_radius = rms_radius(scan);
    if model_radius.is_nan() || model_radius <= 0.0 || scan_radius.is_nan() || scan_radius <= 0.0 {
        return Err(invalid(
            "scan",
            "the scan or the model's mean shape has no extent",
        ));
    }
    let s0 = if options.estimate_scale {
        scan_radius / model_radius
    } else {
        1.0
    };
    let triangles = model.template().triangles();
    let t0 = match options.view_direction {
        // scan centroid minus the offset of the visible part's centroid from the model's, with
        // the mean shape turned to the start
        Some(d) => {
            let turn = SimilarityTransform {
                rotation: start.rotation,
                ..SimilarityTransform::IDENTITY
            };
            let turned: Vec<[f32; 3]> = start_shape
                .iter()
                .map(|p| {
                    let q = turn.apply(std::array::from_fn(|k| (f64::from(p[k]) - c[k]) as f32));
                    std::array::from_fn(|k| (f64::from(q[k]) + c[k]) as f32)
                })
                .collect();
            let visible: Vec<[f32; 3]> = facing_vertices(&turned, triangles, d)?
                .iter()
                .filter_map(|&i| turned.get(i as usize).copied())
                .collect();
            let cv = centroid(&visible);
            let cs = centroid(scan);
            std::array::from_fn(|k| cs[k] - s0 * (cv[k] - c[k]))
        }
        None => centroid(scan),
    };
    let r0 = model_radius * s0;

    let sub: Vec<[f32; 3]> = if scan.len() > options.max_scan_points {
        uniform_sampling(scan.len(), options.max_scan_points, options.seed)?
            .iter()
            .filter_map(|&i| scan.get(i as usize).copied())
            .collect()
    } else {
        scan.to_vec()
    };
    let scan_t = Tensor::from_vec(flatten_points(&sub), (sub.len(), 3), &dev)?;

    let z = Var::from_tensor(&Tensor::from_vec(start.code.clone(), (1, z_size), &dev)?)?;
    let q = Var::from_tensor(&Tensor::new(&start.rotation.map(|x| x as f32), &dev)?)?;
    let log_s = Var::from_tensor(&Tensor::zeros(1, DType::F32, &dev)?)?;
    let tau = Var::from_tensor(&Tensor::zeros((1, 3), DType::F32, &dev)?)?;
    let mut vars = vec![
        ("latent".to_string(), z.clone()),
        ("rotation".to_string(), q.clone()),
        ("translation".to_string(), tau.clone()),
    ];
    if options.fit_scale {
        vars.push(("log_scale".to_string(), log_s.clone()));
    }
    let mut opt = Adam::new(
        vars,
        AdamConfig {
            learning_rate: options.learning_rate,
            ..Default::default()
        },
    )?;
    let c_t = Tensor::from_vec(c.map(|x| x as f32).to_vec(), (1, 3), &dev)?;
    let t0_t = Tensor::from_vec(t0.map(|x| x as f32).to_vec(), (1, 3), &dev)?;
    let prior_t = match prior {
        Some(p) => {
            let mu = Tensor::from_vec(
                p.mean().iter().map(|&m| m as f32).collect::<Vec<_>>(),
                (1, z_size),
                &dev,
            )?;
            let w = Tensor::from_vec(
                p.whitening().iter().map(|&m| m as f32).collect::<Vec<_>>(),
                (z_size, z_size),
                &dev,
            )?
            .t()?
            .contiguous()?;
            Some((mu, w))
        }
        None => None,
    };
    let forward = || -> Result<Tensor> {
        let x = model
            .decode(z.as_tensor())?
            .to_dtype(DType::F32)?
            .squeeze(0)?;
        let r = quaternion_matrix(q.as_tensor())?;
        let s = (log_s.as_tensor().exp()? * s0)?;
        let t = (t0_t.clone() + (tau.as_tensor() * r0)?)?;
        Ok(x.broadcast_sub(&c_t)?
            .matmul(&r.t()?)?
            .broadcast_mul(&s)?
            .broadcast_add(&t)?)
    };
    let loss_of = |y: &Tensor| -> Result<Tensor> {
        let data = match options.direction {
            ChamferDirection::Symmetric => chamfer_loss(y, &scan_t)?,
            ChamferDirection::ScanToModel => directed_chamfer(
                &sub,
                &scan_t,
                y,
                options.view_direction.map(|d| (triangles, d)),
            )?,
        };
        let mut loss = (data / (r0 * r0))?;
        if let Some((mu, w)) = &prior_t {
            let d = z.as_tensor().broadcast_sub(mu)?.matmul(w)?;
            let penalty = (d.sqr()?.sum_all()? * (options.prior_weight / z_size as f64))?;
            loss = (loss + penalty)?;
        }
        Ok(loss)
    };
    for step in 0..options.steps {
        let frac = step as f64 / options.steps as f64;
        opt.set_learning_rate(options.learning_rate * (1.0 - 0.9 * frac));
        let loss = loss_of(&forward()?)?;
        let value = f64::from(loss.to_scalar::<f32>()?);
        if !value.is_finite() {
            return Err(invalid(
                "scan fit",
                format!("the loss became non-finite at step {step}"),
            ));
        }
        opt.backward_step(&loss)?;
    }
    let y = forward()?;
    let final_loss = f64::from(loss_of(&y)?.to_scalar::<f32>()?);
    let vertices = unflatten_points(&y.flatten_all()?.to_vec1::<f32>()?);
    let latent: Vec<f32> = z.as_tensor().flatten_all()?.to_vec1()?;
    let qv: Vec<f32> = q.as_tensor().to_vec1()?;
    let qn = qv
        .iter()
        .map(|&a| f64::from(a).powi(2))
        .sum::<f64>()
        .sqrt()
        .max(1e-30);
    let rotation: [f64; 4] = std::array::from_fn(|k| qv.get(k).map_or(0.0, |&a| f64::from(a) / qn));
    let scale = s0
        * f64::from(
            log_s
                .as_tensor()
                .to_vec1::<f32>()?
                .first()
                .copied()
                .unwrap_or(0.0),
        )
        .exp();
    let tv: Vec<f32> = tau.as_tensor().flatten_all()?.to_vec1()?;
    let t: [f64; 3] =
        std::array::from_fn(|k| t0[k] + r0 * tv.get(k).map_or(0.0, |&a| f64::from(a)));
    // y = s R (x − c) + t = s R x + (t − s R c)
    let rot = SimilarityTransform {
        scale,
        rotation,
        translation: [0.0; 3],
    };
    let rc = rot.apply(c.map(|x| x as f32));
    let transform = SimilarityTransform {
        translation: std::array::from_fn(|k| t[k] - f64::from(rc[k])),
        ..rot
    };
    let distances = scan_distances(&vertices, scan)?;
    Ok(ScanFit {
        vertices,
        latent,
        transform,
        distances,
        loss: final_loss,
        mirrored: false,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::handy::pca::Pca;
    use meshgnn_geometry::icosphere;
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    /// An asymmetric blob with three smooth, linear modes: stretch, bend, shear.
    fn blob(a: f32, b: f32, c: f32) -> Vec<[f32; 3]> {
        icosphere(3)
            .vertices()
            .iter()
            .map(|p| {
                let (x, y, z) = (
                    2.0 * p[0],
                    p[1],
                    0.6 * p[2] + 0.2 * p[0] * p[0] + 0.1 * p[1],
                );
                [
                    x * (1.0 + 0.2 * a),
                    y + 0.3 * c * z + 0.1 * x,
                    z + 0.15 * b * x * x,
                ]
            })
            .collect()
    }

    fn model() -> Pca {
        let mut rng = StdRng::seed_from_u64(11);
        let shapes: Vec<_> = (0..12)
            .map(|_| {
                blob(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                )
            })
            .collect();
        Pca::fit(&icosphere(3), &shapes, 3).unwrap()
    }

    #[test]
    fn recovers_a_known_code_and_similarity_transform() {
        let pca = model();
        let truth_z = [0.9f32, -0.7, 0.5];
        let x = crate::handy::shape_batches::decode_latents(&pca, &[truth_z.to_vec()]).unwrap();
        let truth = SimilarityTransform::from_axis_angle(
            1.15,
            [1.0, 2.0, 3.0],
            12f64.to_radians(),
            [0.4, -0.3, 0.2],
        );
        let scan: Vec<[f32; 3]> = x[0].iter().map(|&p| truth.apply(p)).collect();
        for direction in [ChamferDirection::Symmetric, ChamferDirection::ScanToModel] {
            let opts = ScanFitOptions {
                direction,
                estimate_scale: true,
                steps: 400,
                ..Default::default()
            };
            let fit = fit_scan(&pca, &scan, None, &opts).unwrap();
            for (a, b) in fit.latent.iter().zip(truth_z) {
                assert!((a - b).abs() < 0.05, "{direction:?}: {:?}", fit.latent);
            }
            assert!(
                (fit.transform.scale - 1.15).abs() < 0.01,
                "{:?}",
                fit.transform
            );
            // relative rotation angle
            let inv = SimilarityTransform {
                rotation: {
                    let [w, x, y, z] = truth.rotation;
                    [w, -x, -y, -z]
                },
                ..SimilarityTransform::IDENTITY
            };
            let rel = inv.compose(&fit.transform);
            assert!(
                rel.angle().to_degrees() < 0.5,
                "{}",
                rel.angle().to_degrees()
            );
            for k in 0..3 {
                assert!((fit.transform.translation[k] - truth.translation[k]).abs() < 0.02);
            }
            let err = meshgnn_losses::metrics::per_vertex_error(&fit.vertices, &scan).unwrap();
            assert!(err < 0.01, "{err}");
            assert!(fit.distances.r2s < 0.01 && fit.distances.s2r < 0.01);
        }
    }

    #[test]
    fn global_init_recovers_a_turned_and_mirrored_scan() {
        let pca = model();
        let x = crate::handy::shape_batches::decode_latents(&pca, &[vec![0.5, -0.4, 0.3]]).unwrap();
        let turn = SimilarityTransform::from_axis_angle(
            1.0,
            [1.0, -2.0, 0.5],
            140f64.to_radians(),
            [0.3, 0.1, -0.2],
        );
        // the mirror image of a turned shape: a "left hand" in an unknown orientation
        let scan: Vec<[f32; 3]> = x[0]
            .iter()
            .map(|&p| {
                let q = turn.apply(p);
                [-q[0], q[1], q[2]]
            })
            .collect();
        let opts = ScanFitOptions {
            steps: 400,
            ..Default::default()
        };
        let plain = fit_scan(&pca, &scan, None, &opts).unwrap();
        let global = ScanFitOptions {
            global_init: true,
            ..opts
        };
        let fit = fit_scan(&pca, &scan, None, &global).unwrap();
        assert!(fit.mirrored && !plain.mirrored);
        let err = meshgnn_losses::metrics::per_vertex_error(&fit.vertices, &scan).unwrap();
        assert!(err < 0.02, "per-vertex error {err}");
        assert!(
            plain.distances.s2r > 5.0 * fit.distances.s2r,
            "without the global start {:?}, with it {:?}",
            plain.distances,
            fit.distances
        );
    }

    #[test]
    fn global_init_starts_from_the_modes_of_the_prior() {
        // Training codes in two clusters, the second far from the mean; a turned scan of the
        // far cluster's shape is recovered from the mode nearest it.
        let pca = model();
        let far = [2.5f32, -2.0, 1.5];
        let codes: Vec<Vec<f32>> = (0..60)
            .map(|i| {
                let t = i as f32;
                let jitter = [
                    0.05 * (t * 0.7).sin(),
                    0.05 * (t * 1.1).cos(),
                    0.05 * (t * 1.9).sin(),
                ];
                let centre = if i < 40 { [0.0; 3] } else { far };
                std::array::from_fn::<f32, 3, _>(|k| centre[k] + jitter[k]).to_vec()
            })
            .collect();
        let prior = LatentGaussian::fit(&codes).unwrap();
        let gap = |m: &Vec<f64>| -> f64 {
            m.iter()
                .zip(far)
                .map(|(a, b)| (a - f64::from(b)).powi(2))
                .sum::<f64>()
                .sqrt()
        };
        assert!(
            prior.modes().iter().any(|m| gap(m) < 0.1),
            "{:?}",
            prior.modes()
        );
        let x = crate::handy::shape_batches::decode_latents(&pca, &[far.to_vec()]).unwrap();
        let turn = SimilarityTransform::from_axis_angle(
            1.0,
            [0.2, 1.0, -0.4],
            120f64.to_radians(),
            [0.1, -0.3, 0.2],
        );
        let scan: Vec<[f32; 3]> = x[0].iter().map(|&p| turn.apply(p)).collect();
        let options = ScanFitOptions {
            steps: 400,
            global_init: true,
            ..Default::default()
        };
        let fit = fit_scan(&pca, &scan, Some(&prior), &options).unwrap();
        let err = meshgnn_losses::metrics::per_vertex_error(&fit.vertices, &scan).unwrap();
        assert!(err < 0.02, "per-vertex error {err}");
        assert!(!fit.mirrored);
    }

    #[test]
    fn culling_keeps_the_vertices_facing_the_scanner() {
        // on a unit sphere the vertex normal is the position: facing +z ⇔ z > 0
        let s = icosphere(3);
        let facing = facing_vertices(s.vertices(), s.triangles(), [0.0, 0.0, 1.0]).unwrap();
        let expected: Vec<u32> = (0..s.vertex_count() as u32)
            .filter(|&i| s.vertices()[i as usize][2] > 1e-6)
            .collect();
        assert_eq!(facing, expected);
        // a one-sided scan of the model's own mean shape, moved: with the view direction the
        // fit starts at the visible part and lands on the shape
        let pca = model();
        let mean = crate::handy::shape_batches::decode_latents(&pca, &[vec![0.0; 3]]).unwrap();
        let truth: Vec<[f32; 3]> = mean[0]
            .iter()
            .map(|p| [p[0] + 0.3, p[1] - 0.2, p[2] + 0.1])
            .collect();
        let mesh = TriMesh::new(truth.clone(), pca.template().triangles().to_vec()).unwrap();
        let scan =
            crate::handy::partial_scan::partial_scan(&mesh, [0.0, 0.0, 1.0], 6000, 0.0, 2).unwrap();
        let opts = ScanFitOptions {
            view_direction: Some([0.0, 0.0, 1.0]),
            fit_scale: false,
            ..Default::default()
        };
        let fit = fit_scan(&pca, &scan, Some(&LatentGaussian::standard(3)), &opts).unwrap();
        // the visible side is matched as closely as the true shape's own vertices match it
        // (point-to-vertex distances have a floor set by the vertex spacing)
        let floor = scan_distances(&truth, &scan).unwrap().s2r;
        assert!(
            fit.distances.s2r < 1.2 * floor,
            "{:?} vs {floor}",
            fit.distances
        );
    }

    #[test]
    fn rejects_bad_scans_and_options() {
        let pca = model();
        assert!(fit_scan(&pca, &[[0.0; 3]; 2], None, &ScanFitOptions::default()).is_err());
        let nan = vec![[f32::NAN, 0.0, 0.0]; 5];
        let e = fit_scan(&pca, &nan, None, &ScanFitOptions::default()).unwrap_err();
        assert!(e.to_string().contains("scan point 0"), "{e}");
        let pts = blob(0.0, 0.0, 0.0);
        let opts = ScanFitOptions {
            steps: 0,
            ..Default::default()
        };
        assert!(fit_scan(&pca, &pts, None, &opts).is_err());
        let g = LatentGaussian::standard(2);
        assert!(fit_scan(&pca, &pts, Some(&g), &ScanFitOptions::default()).is_err());
    }

    #[test]
    fn transform_helpers() {
        let a = SimilarityTransform::from_axis_angle(2.0, [0.0, 0.0, 1.0], 0.3, [1.0, 2.0, 3.0]);
        let b = SimilarityTransform::from_axis_angle(0.5, [1.0, 0.0, 0.0], -0.2, [0.0, 1.0, 0.0]);
        let p = [0.3f32, -0.7, 1.1];
        let ab = a.compose(&b).apply(p);
        let seq = a.apply(b.apply(p));
        for k in 0..3 {
            assert!((ab[k] - seq[k]).abs() < 1e-5);
        }
        assert!((a.angle() - 0.3).abs() < 1e-12);
    }
}
