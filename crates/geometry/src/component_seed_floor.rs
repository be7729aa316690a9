//! A floor on the seeds of each connected component for vertex-selecting simplifiers (the
//! neural mesh simplifier of thesis ch. 6, beyond the thesis): a part of the input that
//! holds too few kept vertices loses its faces, as a leg of a model stored as separate parts
//! does at a low ratio. QEM keeps every part (a collapse that makes a component vanish is
//! rejected); this gives the selection a part's worth of vertices to do the same.

use crate::connected_components::{UNREFERENCED, connected_components};
use crate::tri_mesh::TriMesh;
use crate::vec3::squared_distance_f64;

/// Kept vertices a connected component holds at least, where it holds any. A closed surface
/// needs four (a tetrahedron), but on an elongated part (a leg) four farthest points lie
/// nearly on a line and the face classifier keeps few of their sliver faces; five give a
/// bipyramid. Measured on the data-fixtures ant (15 parts) at 5 %, floors of 4 / 5 / 6 / 8:
/// 47-63 / 64-71 / 89-94 / 133-139 faces against QEM's 78, CD 3.3 / 1.4 / 0.6 / 0.2× QEM's;
/// 5 is the largest that stays below QEM's face count (docs/mesh_simplifier_model.md,
/// "Welded input, a seed floor per part").
pub const MIN_COMPONENT_SEEDS: usize = 5;

/// `seeds` followed, for every connected component of `mesh` that holds between one and
/// [`MIN_COMPONENT_SEEDS`]` − 1` of them, by its vertices farthest from its seeds (farthest
/// point sampling in space, the first in index order on a tie) until it holds
/// `MIN_COMPONENT_SEEDS` or all its vertices; components from the largest (most vertices;
/// the lower label on a tie), at most `max_added` seeds in all, so that a cloud of separate
/// triangles is not turned into all its vertices. Components without a seed stay without.
/// O(V + F + S + C log C) plus O(V_c) per added seed.
///
/// ```
/// use meshgnn_geometry::{TriMesh, component_seed_floor, icosphere};
/// // Two spheres: the first holds one seed, the second none.
/// let sphere = icosphere(1);
/// let n = sphere.vertex_count() as u32;
/// let two = TriMesh::new(
///     sphere.vertices().iter().chain(sphere.vertices()).copied().collect(),
///     sphere.triangles().iter().copied()
///         .chain(sphere.triangles().iter().map(|t| t.map(|v| v + n)))
///         .collect(),
/// )?;
/// let floored = component_seed_floor(&two, &[0], 10);
/// assert_eq!(floored.len(), meshgnn_geometry::MIN_COMPONENT_SEEDS);
/// assert!(floored.iter().all(|&v| v < n));
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn component_seed_floor(mesh: &TriMesh, seeds: &[u32], max_added: usize) -> Vec<u32> {
    let (count, label) = connected_components(mesh);
    let mut size = vec![0usize; count];
    for &l in label.iter().filter(|&&l| l != UNREFERENCED) {
        size[l as usize] += 1;
    }
    let mut held = vec![0usize; count];
    for &s in seeds {
        if let Some(c) = component_of(&label, s) {
            held[c] += 1;
        }
    }
    let short = |c: usize| (1..MIN_COMPONENT_SEEDS).contains(&held[c]);
    if !(0..count).any(short) {
        return seeds.to_vec();
    }
    // The vertices and the seeds of the short components, grouped by component.
    let mut members: Vec<Vec<u32>> = vec![Vec::new(); count];
    let mut own_seeds: Vec<Vec<u32>> = vec![Vec::new(); count];
    for v in 0..label.len() as u32 {
        if let Some(c) = component_of(&label, v).filter(|&c| short(c)) {
            members[c].push(v);
        }
    }
    for &s in seeds {
        if let Some(c) = component_of(&label, s).filter(|&c| short(c)) {
            own_seeds[c].push(s);
        }
    }
    let squared_distance = |a: u32, b: u32| {
        squared_distance_f64(&mesh.vertices()[a as usize], &mesh.vertices()[b as usize])
    };
    let mut order: Vec<usize> = (0..count).filter(|&c| short(c)).collect();
    order.sort_unstable_by_key(|&c| (std::cmp::Reverse(size[c]), c));
    let mut out = seeds.to_vec();
    let limit = seeds.len() + max_added;
    for c in order {
        let vertices = &members[c];
        let mut nearest: Vec<f64> = vertices
            .iter()
            .map(|&v| {
                own_seeds[c]
                    .iter()
                    .map(|&s| squared_distance(v, s))
                    .fold(f64::INFINITY, f64::min)
            })
            .collect();
        let want = MIN_COMPONENT_SEEDS.min(vertices.len());
        for _ in held[c]..want {
            if out.len() == limit {
                return out;
            }
            // The first vertex at the largest distance; 0 once every vertex is a seed.
            let (far, &d) = nearest
                .iter()
                .enumerate()
                .fold((0, &-1.0), |best, x| if x.1 > best.1 { x } else { best });
            if d <= 0.0 {
                break;
            }
            let added = vertices[far];
            out.push(added);
            for (n, &v) in nearest.iter_mut().zip(vertices) {
                *n = n.min(squared_distance(v, added));
            }
        }
    }
    out
}

/// The component of vertex `v`, `None` when no face uses it or it is out of range.
fn component_of(label: &[u32], v: u32) -> Option<usize> {
    label
        .get(v as usize)
        .filter(|&&l| l != UNREFERENCED)
        .map(|&l| l as usize)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit square of 5 × 5 vertices (vertices 0-24) and a tetrahedron (25-28) beside it.
    fn square_and_tetrahedron() -> TriMesh {
        let square = crate::grid_plane(4, 4);
        let mut vertices = square.vertices().to_vec();
        vertices.extend([
            [3.0, 0.0, 0.0],
            [4.0, 0.0, 0.0],
            [3.0, 1.0, 0.0],
            [3.0, 0.0, 1.0],
        ]);
        let mut faces = square.triangles().to_vec();
        faces.extend([[25, 27, 26], [25, 26, 28], [25, 28, 27], [26, 27, 28]]);
        TriMesh::new(vertices, faces).unwrap()
    }

    #[test]
    fn short_components_get_their_farthest_vertices() {
        assert_eq!(MIN_COMPONENT_SEEDS, 5);
        let mesh = square_and_tetrahedron();
        // One seed at the square's corner (0, 0): the opposite corner (1, 1) is farthest,
        // then the two other corners, (1, 0) first in index order, then the centre. The
        // tetrahedron has none and stays without.
        assert_eq!(component_seed_floor(&mesh, &[0], 9), vec![0, 24, 4, 20, 12]);
        // Three corners and the centre: the fourth corner, √½ from the centre. Two in the
        // tetrahedron, (4, 0, 0) and (3, 1, 0): (3, 0, 1) is √2 from both, then (3, 0, 0),
        // 1 from both; it has no fifth vertex.
        let seeds = [0, 12, 24, 4, 26, 27];
        assert_eq!(
            component_seed_floor(&mesh, &seeds, 3),
            vec![0, 12, 24, 4, 26, 27, 20, 28, 25]
        );
        // At most `max_added`, larger components first: the square (25 vertices) before
        // the tetrahedron (4).
        assert_eq!(
            component_seed_floor(&mesh, &seeds, 2),
            vec![0, 12, 24, 4, 26, 27, 20, 28]
        );
        assert_eq!(component_seed_floor(&mesh, &seeds, 0), seeds);
        // Every component at the floor (or without seeds): unchanged.
        let full = [3, 7, 11, 15, 19, 25, 26, 27, 28];
        assert_eq!(component_seed_floor(&mesh, &full, 9), full);
    }

    #[test]
    fn a_component_of_three_vertices_gets_all_three() {
        let mesh = TriMesh::new(
            vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [9.0, 9.0, 9.0]],
            vec![[0, 1, 2]],
        )
        .unwrap();
        // Vertex 3 is used by no face: part of no component, kept as given.
        assert_eq!(component_seed_floor(&mesh, &[1, 3], 9), vec![1, 3, 2, 0]);
    }
}
