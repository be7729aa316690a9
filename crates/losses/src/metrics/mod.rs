//! Evaluation metrics as plain Rust (f64 accumulation, rayon, `SpatialIndex` nearest neighbours).

mod chamfer;
mod comparison_table;
mod curvature_error;
mod hausdorff;
mod laplacian_error;
mod matched_scale_curvature;
mod mesh_evaluation;
mod morphable_model;
mod nearest_value_error;
mod normal_consistency;
mod normals_error;
mod pc_msdm;
mod per_vertex_error;
mod point_cloud_evaluation;
mod roughness_error;
mod structural_distortion;
mod watertightness;

pub use chamfer::{ChamferDistance, chamfer_distance};
pub use comparison_table::{TableColumn, comparison_table};
pub use curvature_error::curvature_error;
pub use hausdorff::hausdorff_distance;
pub use laplacian_error::{LAPLACIAN_EIGENVECTORS, laplacian_error};
pub use matched_scale_curvature::{
    CurvatureReference, MatchedScaleCurvature, REFERENCE_OVERSAMPLING, REFERENCE_SEED,
    curvature_reference, matched_scale_curvature,
};
pub use mesh_evaluation::{
    MAX_MESH_EVALUATION_SAMPLES, MESH_EVALUATION_SAMPLES, MeshEvaluation, mesh_evaluation,
};
pub use morphable_model::{
    CentredShapes, Compactness, ErrorSummary, centred_shapes, compactness, generalisation,
    specificity,
};
pub use nearest_value_error::nearest_value_error;
pub use normal_consistency::{NormalOrientation, normal_consistency};
pub use normals_error::normals_error;
pub use pc_msdm::{PcMsdmParams, pc_msdm};
pub use per_vertex_error::per_vertex_error;
pub use point_cloud_evaluation::{
    EVALUATION_CURVATURE_NEIGHBOURS, MAX_EVALUATION_CURVATURE_NEIGHBOURS, PointCloudEvaluation,
    point_cloud_evaluation, point_cloud_evaluation_at_scale,
};
pub use roughness_error::roughness_error;
pub use structural_distortion::{SdmParams, structural_distortion};
pub use watertightness::watertightness;
