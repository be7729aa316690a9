//! Bounds on the user-given counts of this crate's computations (training, decoding, scan
//! fitting). Callers check a count with `meshgnn_geometry::check_count` against these before
//! allocating; each bound says what it caps. The list of every bound is in docs/security.md.

/// Most shapes decoded in one call of [`crate::decode_latents`] or
/// [`crate::interpolate_shapes`] (`handy sample -n`, `handy interpolate --steps`): each shape
/// is kept as a mesh and drawn as a 256×256 contact-sheet tile (192 KB), so the bound keeps a
/// run under about 1 GB (a mesh of the 11 265-vertex template is 135 KB) instead of growing
/// without writing anything.
pub const MAX_DECODED_SHAPES: usize = 1000;

/// Most Adam steps of one scan fit ([`crate::ScanFitOptions::steps`], `handy fit --steps`,
/// `handy eval --fit-steps`); the default is 300. Memory does not grow with the steps, time
/// does, so the bound stops a typo from running for days.
pub const MAX_FIT_STEPS: usize = 100_000;

/// Most random shapes of the specificity measure ([`crate::specificity_error`],
/// `handy eval --samples`; the thesis uses 1000): every sample is decoded and compared with
/// every training shape, so time grows with samples × training shapes.
pub const MAX_SPECIFICITY_SAMPLES: usize = 100_000;

/// Most training epochs (`handy train --epochs`, `pcsimplify train --epochs`); a checkpoint is
/// written after every epoch, so a long run can stop and resume.
pub const MAX_EPOCHS: usize = 100_000;

/// Most shapes per training step (`handy train --batch-size`): activations grow with batch ×
/// vertices × channels (one 64-channel layer of an 11 265-vertex hand is 2.9 MB in `f32`).
pub const MAX_BATCH_SIZE: usize = 1024;

/// Largest latent code (`handy train --latent`; the thesis uses 8 and 30): the fully connected
/// layers hold latent × coarsest-level features weights.
pub const MAX_LATENT_SIZE: usize = 1024;

/// Most points per training cloud of the point simplifier (`pcsimplify train --points`; the
/// default is 2048): each cloud keeps its k-NN graph, curvature and per-point activations for
/// the whole run.
pub const MAX_TRAINING_CLOUD_POINTS: usize = 65_536;

/// Most differently sampled training clouds per mesh (`pcsimplify train --clouds-per-shape`).
pub const MAX_CLOUDS_PER_SHAPE: usize = 64;
