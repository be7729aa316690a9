//! The mesh simplification report of thesis ch. 6.5.1 (Table 6.1): CD, NE, WA, LE, plus the
//! Hausdorff distance, hole count and edge-manifoldness.

use crate::Result;
use crate::metrics::chamfer::chamfer_distance;
use crate::metrics::hausdorff::hausdorff_distance;
use crate::metrics::laplacian_error::{LAPLACIAN_EIGENVECTORS, laplacian_error};
use crate::metrics::normals_error::normals_error;
use crate::metrics::watertightness::watertightness;
use meshgnn_geometry::{TriMesh, mesh_report, sample_surface, unit_sphere_normalization};

/// The number of surface samples of ch. 6.5.1.
pub const MESH_EVALUATION_SAMPLES: usize = 50_000;

/// Metrics of a simplified mesh against its original, both normalised by the original's
/// centroid and bounding-sphere radius (so lengths are in units of that radius).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshEvaluation {
    /// Chamfer distance (eq. 5.6, per-point means of both directions) between surface samples,
    /// squared unit-sphere units.
    pub cd: f64,
    /// Hausdorff distance between the surface samples, unit-sphere units.
    pub hausdorff: f64,
    /// Normal error NE (eq. 6.15), dimensionless in [0, 4].
    pub ne: f64,
    /// Watertightness WA: percentage of the simplified mesh's edges with valence ≠ 2.
    pub wa: f64,
    /// Laplacian error LE (eq. 6.16, see [`super::laplacian_error`]), dimensionless.
    pub le: f64,
    /// Boundary loops (holes and rims) of the simplified mesh.
    pub holes: usize,
    /// No edge of the simplified mesh has more than two faces.
    pub edge_manifold: bool,
}

/// Evaluates `simplified` against `original`: normalises both by the original's unit sphere,
/// samples `samples` points (50 000 in the thesis) on each surface (area-weighted, from `seed`
/// and `seed + 1`), and computes every field of [`MeshEvaluation`].
///
/// Fails when a mesh has no area or the Laplacian eigen-solve fails.
///
/// ```
/// use meshgnn_geometry::subdivided_cube;
/// use meshgnn_losses::metrics::mesh_evaluation;
/// let cube = subdivided_cube(3);
/// let e = mesh_evaluation(&cube, &cube, 2000, 1)?;
/// assert!(e.ne < 1e-12 && e.wa == 0.0 && e.holes == 0 && e.edge_manifold);
/// assert!(e.cd == 0.0 && e.hausdorff == 0.0 && e.le < 1e-9);
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn mesh_evaluation(
    original: &TriMesh,
    simplified: &TriMesh,
    samples: usize,
    seed: u64,
) -> Result<MeshEvaluation> {
    let norm = unit_sphere_normalization(original.vertices())?;
    let a = original
        .clone()
        .with_vertices(norm.apply(original.vertices()))?;
    let b = simplified
        .clone()
        .with_vertices(norm.apply(simplified.vertices()))?;
    // One seed for both: a mesh compared with itself gets the same samples and scores 0.
    let (sa, sb) = rayon::join(
        || sample_surface(&a, samples, seed),
        || sample_surface(&b, samples, seed),
    );
    let (sa, sb) = (sa?, sb?);
    let cd = chamfer_distance(&sa.points, &sb.points)?.symmetric_mean();
    let hausdorff = hausdorff_distance(&sa.points, &sb.points)?;
    let ne = normals_error(&a, &b)?;
    let le = laplacian_error(&a, &b, LAPLACIAN_EIGENVECTORS)?;
    let report = mesh_report(&b);
    Ok(MeshEvaluation {
        cd,
        hausdorff,
        ne,
        wa: watertightness(&b),
        le,
        holes: report.boundary_loops,
        edge_manifold: report.edge_manifold,
    })
}
