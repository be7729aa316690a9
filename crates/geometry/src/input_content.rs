//! Whether a mesh or cloud read from a user's file holds what a command needs: vertices,
//! coordinates the operators can square without overflow, and (for commands that work on the
//! surface) faces of positive area.
//!
//! Readers accept every well-formed file, and a well-formed file can be empty: an empty
//! `.obj`, or text with no `v` record, parses as a mesh of zero vertices. Every command reads
//! through [`read_input_mesh`] or [`read_input_point_cloud`] (or calls [`check_input_points`]
//! right after reading a mesh-or-cloud), so such a file is a
//! one-line error naming it and the problem, never a silent "vertices 0" or an error deep in
//! a solver that names the wrong input.

use std::path::Path;

use crate::error::{Error, Result};
use crate::face_normals::face_areas;
use crate::{PointCloud, TriMesh, read_mesh, read_point_cloud};

/// Reads the mesh at `path` and checks that it holds what `usage` needs
/// ([`check_input_mesh`]): what every command that takes a mesh file calls.
pub fn read_input_mesh(path: &Path, usage: InputUse) -> Result<TriMesh> {
    let mesh = read_mesh(path)?;
    check_input_mesh(path, &mesh, usage)?;
    Ok(mesh)
}

/// Reads the point cloud at `path` (a mesh file's vertices) and checks it
/// ([`check_input_points`]): what every command that takes a cloud file calls.
pub fn read_input_point_cloud(path: &Path) -> Result<PointCloud> {
    let cloud = read_point_cloud(path)?;
    check_input_points(path, cloud.points())?;
    Ok(cloud)
}

/// Largest coordinate magnitude accepted from a file. Positions are `f32` and the spatial
/// index, normals and curvature square coordinate differences in `f32`: with `|x| ≤ 1e18` a
/// squared distance stays below `1.2e37`, inside `f32::MAX ≈ 3.4e38`. Real data (metres,
/// millimetres, even micrometres of a planet) stays far below it.
pub const MAX_COORDINATE_MAGNITUDE: f32 = 1e18;

/// What a command does with an input mesh, hence what the mesh must hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InputUse {
    /// Only its vertices (`meshsimplify info`, point-cloud commands): at least one.
    Points,
    /// Its surface (simplification, evaluation, surface sampling): at least one face, and a
    /// positive total area.
    Surface,
}

/// Fails unless `points: #P×3`, read from `path`, holds at least one point and every
/// coordinate is within ±[`MAX_COORDINATE_MAGNITUDE`]. The error names `path`.
///
/// ```
/// use meshgnn_geometry::check_input_points;
/// let path = std::path::Path::new("scan.xyz");
/// assert!(check_input_points(path, &[[0.0, 1.0, 2.0]]).is_ok());
/// let err = check_input_points(path, &[]).unwrap_err().to_string();
/// assert!(err.starts_with("scan.xyz: ") && err.contains("no vertices"), "{err}");
/// assert!(check_input_points(path, &[[1e38, 0.0, 0.0]]).is_err());
/// ```
pub fn check_input_points(path: &Path, points: &[[f32; 3]]) -> Result<()> {
    let fail = |element: String, message: String| Error::Format {
        path: path.to_path_buf(),
        element,
        message,
    };
    if points.is_empty() {
        return Err(fail(
            "content".into(),
            "no vertices: the file is empty or is not in the format its extension names".into(),
        ));
    }
    // NaN fails the `is_some_and` too, so it counts as outside.
    let outside = |c: &f32| {
        !c.abs()
            .partial_cmp(&MAX_COORDINATE_MAGNITUDE)
            .is_some_and(|o| o.is_le())
    };
    if let Some((index, p)) = points
        .iter()
        .enumerate()
        .find(|(_, p)| p.iter().any(outside))
    {
        let value = p.iter().copied().find(outside).unwrap_or(f32::NAN);
        return Err(fail(
            format!("vertex {index}"),
            format!(
                "coordinate {value:e} is beyond ±{MAX_COORDINATE_MAGNITUDE:e}, the largest \
                 magnitude the operators support (squared distances would overflow): rescale \
                 the model"
            ),
        ));
    }
    Ok(())
}

/// Fails unless `mesh`, read from `path`, holds what `usage` needs: vertices with supported
/// coordinates ([`check_input_points`]) and, for [`InputUse::Surface`], at least one face and
/// a positive total area. The error names `path` and the problem.
///
/// ```
/// use meshgnn_geometry::{InputUse, TriMesh, check_input_mesh, icosphere};
/// let path = std::path::Path::new("scan.obj");
/// check_input_mesh(path, &icosphere(1), InputUse::Surface)?;
/// let cloud = TriMesh::new(vec![[0.0; 3], [1.0, 0.0, 0.0]], vec![])?;
/// assert!(check_input_mesh(path, &cloud, InputUse::Points).is_ok());
/// let err = check_input_mesh(path, &cloud, InputUse::Surface).unwrap_err().to_string();
/// assert_eq!(
///     err,
///     "scan.obj: mesh: 2 vertices but no faces: a point cloud, not a surface (this command \
///      needs triangles)"
/// );
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn check_input_mesh(path: &Path, mesh: &TriMesh, usage: InputUse) -> Result<()> {
    check_input_points(path, mesh.vertices())?;
    if usage == InputUse::Points {
        return Ok(());
    }
    let fail = |message: String| Error::Format {
        path: path.to_path_buf(),
        element: "mesh".into(),
        message,
    };
    if mesh.face_count() == 0 {
        return Err(fail(format!(
            "{} vertices but no faces: a point cloud, not a surface (this command needs \
             triangles)",
            mesh.vertex_count()
        )));
    }
    let area: f64 = face_areas(mesh).iter().sum();
    if !area.partial_cmp(&0.0).is_some_and(|o| o.is_gt()) {
        return Err(fail(format!(
            "all {} faces have zero area (repeated or collinear vertices): there is no surface",
            mesh.face_count()
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn message(result: Result<()>) -> String {
        match result {
            Ok(()) => String::new(),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn each_problem_names_the_file_and_the_element() {
        let path = Path::new("dir/in.ply");
        let empty = TriMesh::default();
        assert_eq!(
            message(check_input_mesh(path, &empty, InputUse::Points)),
            "dir/in.ply: content: no vertices: the file is empty or is not in the format its \
             extension names"
        );
        let far = [[0.0, 0.0, 0.0], [0.0, -2e18, 0.0]];
        let text = message(check_input_points(path, &far));
        assert!(
            text.starts_with("dir/in.ply: vertex 1: coordinate -2e18"),
            "{text}"
        );
        let flat = TriMesh::new(
            vec![[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]],
            vec![[0, 1, 2], [0, 0, 1]],
        )
        .unwrap_or_default();
        assert_eq!(
            message(check_input_mesh(path, &flat, InputUse::Surface)),
            "dir/in.ply: mesh: all 2 faces have zero area (repeated or collinear vertices): \
             there is no surface"
        );
        assert_eq!(message(check_input_mesh(path, &flat, InputUse::Points)), "");
    }

    #[test]
    fn the_largest_supported_coordinate_passes() {
        let edge = [[MAX_COORDINATE_MAGNITUDE, -MAX_COORDINATE_MAGNITUDE, 0.0]];
        assert_eq!(message(check_input_points(Path::new("a.xyz"), &edge)), "");
    }
}
