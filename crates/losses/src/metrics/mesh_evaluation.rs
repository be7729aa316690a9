//! The mesh simplification report of thesis ch. 6.5.1 (Table 6.1): CD, NE, WA, LE, plus the
//! Hausdorff distance, hole count and edge-manifoldness.

use crate::metrics::chamfer::chamfer_distance;
use crate::metrics::hausdorff::hausdorff_distance;
use crate::metrics::laplacian_error::{LAPLACIAN_EIGENVECTORS, laplacian_error};
use crate::metrics::normals_error::normals_error;
use crate::metrics::watertightness::watertightness;
use crate::{Error, Result};
use meshgnn_geometry::{
    MAX_SURFACE_SAMPLES, TriMesh, check_count, face_areas, mesh_report, sample_surface,
    unit_sphere_normalization,
};

/// The number of surface samples of ch. 6.5.1.
pub const MESH_EVALUATION_SAMPLES: usize = 50_000;

/// Most surface samples per mesh [`mesh_evaluation`] accepts: the geometry crate's
/// [`MAX_SURFACE_SAMPLES`] (two clouds and their spatial indices, about 1 GB at the bound).
pub const MAX_MESH_EVALUATION_SAMPLES: usize = MAX_SURFACE_SAMPLES;

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
/// Fails, naming the `original mesh` or the `simplified mesh`, when a mesh has no vertices,
/// no faces or no area, or when its Laplacian eigen-solve fails; fails on `samples` outside
/// `1..=`[`MAX_MESH_EVALUATION_SAMPLES`] before anything is allocated.
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
    check_count(
        "samples",
        samples,
        1..=MAX_MESH_EVALUATION_SAMPLES,
        "surface samples per mesh for CD and Hausdorff",
    )?;
    check_surface("original mesh", original)?;
    check_surface("simplified mesh", simplified)?;
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
    let of = |what: &'static str| move |error| Error::GeometryOf { what, error };
    let (sa, sb) = (
        sa.map_err(of("original mesh"))?,
        sb.map_err(of("simplified mesh"))?,
    );
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

/// Fails, naming `what`, unless `mesh` has vertices and faces of positive total area: the
/// metrics sample its surface and solve its Laplacian.
fn check_surface(what: &'static str, mesh: &TriMesh) -> Result<()> {
    let problem = if mesh.vertex_count() == 0 {
        "no vertices".to_string()
    } else if mesh.face_count() == 0 {
        format!(
            "{} vertices but no faces: there is no surface to sample",
            mesh.vertex_count()
        )
    } else if !face_areas(mesh)
        .iter()
        .sum::<f64>()
        .partial_cmp(&0.0)
        .is_some_and(|o| o.is_gt())
    {
        format!(
            "all {} faces have zero area: there is no surface to sample",
            mesh.face_count()
        )
    } else {
        return Ok(());
    };
    Err(Error::InvalidParameter {
        name: what,
        message: problem,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshgnn_geometry::subdivided_cube;

    fn message(original: &TriMesh, simplified: &TriMesh, samples: usize) -> String {
        match mesh_evaluation(original, simplified, samples, 0) {
            Ok(_) => String::new(),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn each_bad_input_is_named() {
        let cube = subdivided_cube(2);
        let empty = TriMesh::default();
        let cloud = TriMesh::new(cube.vertices().to_vec(), Vec::new()).unwrap_or_default();
        let flat =
            TriMesh::new(vec![[0.0; 3], [1.0, 0.0, 0.0]], vec![[0, 1, 1]]).unwrap_or_default();
        assert_eq!(
            message(&empty, &cube, 100),
            "invalid original mesh: no vertices"
        );
        assert_eq!(
            message(&cube, &empty, 100),
            "invalid simplified mesh: no vertices"
        );
        assert_eq!(
            message(&cloud, &cube, 100),
            format!(
                "invalid original mesh: {} vertices but no faces: there is no surface to sample",
                cube.vertex_count()
            )
        );
        assert_eq!(
            message(&cube, &flat, 100),
            "invalid simplified mesh: all 1 faces have zero area: there is no surface to sample"
        );
    }

    #[test]
    fn the_sample_count_is_bounded_before_sampling() {
        let cube = subdivided_cube(2);
        assert!(message(&cube, &cube, 0).starts_with("invalid samples: 0 is outside 1..="));
        let huge = message(&cube, &cube, MAX_MESH_EVALUATION_SAMPLES + 1);
        assert!(
            huge.starts_with("invalid samples: 10000001 is outside"),
            "{huge}"
        );
    }
}
