//! Bounds on the user-given counts of the dataset generators and previews (`synth -n`,
//! `--per-family`, `--resolution`, `--lidar`, contact sheets). Callers check a count with
//! `meshgnn_geometry::check_count` against these before generating anything; each bound says
//! what it caps. The list of every bound is in docs/security.md.

/// Most subjects of `synth hands` ([`crate::HandSetConfig::count`]): one binary PLY each
/// (12 bytes per vertex and 13 per face, about 0.4 MB at the default 11 265-vertex
/// resolution), so the bound is about 40 GB of files; memory holds only the labels (a few
/// hundred bytes per subject).
pub const MAX_HAND_SUBJECTS: usize = 100_000;

/// Most subjects of `synth faces` ([`crate::FaceSetConfig::subjects`]): each writes six
/// expression sequences of 12 to 20 frames at the default frame step, about 100 meshes, so
/// the bound is a million files.
pub const MAX_FACE_SUBJECTS: usize = 10_000;

/// Most shapes per family of `synth shapes` (five families, each shape written clean and
/// noisy).
pub const MAX_SHAPES_PER_FAMILY: usize = 1000;

/// Largest grid resolution of `synth shapes` (cells along the longest side of
/// [`crate::marching_tetrahedra`]'s box): the signed distances of one shape take
/// `8 (resolution + 1)³` bytes, 1.1 GB at the bound, and one shape is meshed per core.
pub const MAX_SHAPE_RESOLUTION: usize = 512;

/// Most LiDAR scenes of `synth shapes --lidar` (about 2 M points each, generated one at a
/// time).
pub const MAX_LIDAR_SCENES: usize = 100;

/// Most pixels of one contact sheet ([`crate::contact_sheet`], every `--preview` PNG): 3 bytes
/// each, so 192 MB at the bound (1024 tiles of 256×256).
pub const MAX_PREVIEW_PIXELS: usize = 1 << 26;
