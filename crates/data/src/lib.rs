//! # meshgnn-data
//!
//! Synthetic datasets for the meshgnn models, generated here because no data can be
//! downloaded (SPEC §5), and registered-mesh folder datasets so users bring their own:
//!
//! - **Hands** (thesis ch. 3.3-3.4): one fixed-topology procedural template, per-subject
//!   shape from age 1 to 81 (children's proportions, Table 3.2), and articulation.
//! - **Faces** (thesis ch. 4.3-4.4): a head template with identity parameters, the six 4DFAB
//!   expressions as non-linear muscle-like actions, per-subject expression styles, and 4D
//!   sequences with motion labels and the intensity scaling of eq. 4.3.
//! - **Simplification shapes** (thesis ch. 5.5, 6.5): meshes from signed distance functions
//!   (CAD-like solids, blended creatures), noisy scans (ch. 5.5.7), LiDAR-like point clouds,
//!   with shape-family-disjoint splits.
//! - **Folder datasets**: a directory of registered meshes plus a `dataset.json` manifest.
//!
//! Every generator is deterministic from a `seed: u64`, whatever the thread count.
//! Dependencies beyond the workspace's usual set: `png` (contact-sheet previews) and
//! `serde_json` (manifests).
//!
//! # Conventions
//! - Positions `[f32; 3]`; internal geometry in `f64`. Hands and faces are in millimetres.
//! - Triangles are counter-clockwise seen from outside.
#![cfg_attr(not(test), warn(clippy::unwrap_used, clippy::expect_used))]

mod catmull_clark;
mod count_bounds;
mod error;
mod expression_labels;
mod expression_sequence;
mod expression_style;
mod expressions;
mod face_template;
mod folder_dataset;
mod hand_dataset;
mod hand_gesture;
mod hand_pose;
mod hand_shape;
mod hand_template;
mod point_preview;
mod preview;
mod self_intersections;
mod shapes;
mod vec3;

pub use catmull_clark::{QuadSubdivision, catmull_clark};
pub use count_bounds::{
    MAX_FACE_SUBJECTS, MAX_HAND_SUBJECTS, MAX_LIDAR_SCENES, MAX_PREVIEW_PIXELS,
    MAX_SHAPE_RESOLUTION, MAX_SHAPES_PER_FAMILY,
};
pub use error::{Error, Result};
pub use expression_labels::{ExpressionLabels, FrameLabel, SequenceStats};
pub use expression_sequence::{
    FaceSequence, FaceSetConfig, FaceSubject, SequenceTiming, intensity_scale, intensity_scales,
};
pub use expression_style::ExpressionStyle;
pub use expressions::{Actions, Expression, apply_actions, apply_styled_actions};
pub use face_template::{FaceIdentity, FaceTemplate};
pub use folder_dataset::{FolderDataset, MANIFEST_FILE, Manifest, write_dataset, write_manifest};
pub use hand_dataset::{
    CHILD_AGE, FreeHand, HandSample, HandSetConfig, SHAPE_DRAWS, hand_splits, relax_until_free,
};
pub use hand_gesture::{HandGesture, random_hand_pose};
pub use hand_pose::{
    FINGER_FLEXION_DEG, HandPose, OPPOSITION_DEG, SPREAD_DEG, THUMB_FLEXION_DEG, WRIST_DEG,
};
pub use hand_shape::{FINGER_NAMES, HandShape};
pub use hand_template::{DEFAULT_HAND_SUBDIVISIONS, HandTemplate};
pub use point_preview::{ColoredPoints, point_cloud_sheet, points_on_mesh_sheet, value_colors};
pub use preview::{RgbImage, View, contact_sheet, encode_png, render_mesh, write_png};
pub use self_intersections::{self_intersecting_pairs, self_intersections};
pub use shapes::{
    LidarConfig, ShapeFamily, gaussian_noise, lidar_scene, marching_tetrahedra, noisy_scan,
    shape_mesh,
};
