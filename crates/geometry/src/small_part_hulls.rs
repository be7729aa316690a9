//! Closed small parts for vertex-selecting simplifiers (the neural mesh simplifier of thesis
//! ch. 6, beyond the thesis): a closed part of the input that keeps only a handful of
//! vertices, a leg of a model stored as separate parts, is a bipyramid's worth of points, and
//! the face classifier keeps few of its sliver faces (the data-fixtures ant at 5 %: 0-4 of the
//! 6 a closed leg needs, so its legs came out as loose slivers or not at all). Such a part,
//! when the faces kept on it do not close it, becomes the convex hull of its kept vertices,
//! closed as QEM keeps it (docs/mesh_simplifier_model.md, "Small parts closed by their hull").

use crate::connected_components::{UNREFERENCED, connected_components};
use crate::convex_hull::convex_hull;
use crate::error::{Error, Result};
use crate::manifold::has_pinched_vertex;
use crate::tri_mesh::TriMesh;
use crate::vec3::{norm, triangle_cross};

/// The most surface a part's hull may have, as a multiple of the part's own area. The hull of
/// points on a convex part never has more area than the part (surface area grows with convex
/// sets); on the ant, a bent leg's hull has 1.4-1.9 times its leg's area and is closer to it
/// than the faces the network kept, while a curled antenna's hull, a panel across the curl,
/// has 2.3-3.1 times and is not (CD at 20 % 2.51× QEM's with every hull, 2.27× with this
/// bound, 2.28× with none; docs/mesh_simplifier_model.md, "Small parts closed by their hull").
pub const MAX_HULL_AREA_RATIO: f64 = 2.0;

/// A closed part of the input that the output leaves open (see [`rebuild_small_open_parts`]).
#[derive(Debug, Clone, Copy)]
pub struct OpenPart<'a> {
    /// The output vertices on the part, ascending (output vertex `i` stands for input vertex
    /// `kept[i]`).
    pub members: &'a [u32],
    /// The part's input faces.
    pub faces: &'a [[u32; 3]],
}

/// `output` with the faces of each small open part replaced by its hull.
///
/// Output vertex `i < kept.len()` stands for input vertex `kept[i]`; later output vertices
/// (added by hole filling) belong to no part. A part is a connected component of `input`
/// whose every edge has two faces (closed) and which holds from 4 to `max_kept` output
/// vertices; it is replaced when the output faces with a corner on it are not a closed surface
/// over its vertices and vertices of no part (none, a border, an edge of three faces, a face
/// reaching another part, or a vertex where two closed pieces of it touch). Its replacement:
/// every such face dropped, the [`convex_hull`] of its output vertices added after the other
/// faces (parts in the order of their smallest input vertex).
/// A part whose vertices lie in one plane, or whose hull has more than
/// [`MAX_HULL_AREA_RATIO`] times its area, keeps its faces. The output stays edge-manifold
/// where it was: a hull's vertices carry only its own faces. Vertices are unchanged.
///
/// Errors when `kept` is longer than the output's vertices or names a vertex `input` lacks.
///
/// ```
/// use meshgnn_geometry::{TriMesh, hull_small_open_parts, icosphere};
/// let sphere = icosphere(1);
/// // Five kept vertices of the sphere with one loose face among them.
/// let kept = [0u32, 1, 2, 3, 4];
/// let vertices: Vec<[f32; 3]> = kept.iter().map(|&v| sphere.vertices()[v as usize]).collect();
/// let loose = TriMesh::new(vertices, vec![[0, 1, 2]])?;
/// let closed = hull_small_open_parts(&sphere, &kept, &loose, 5)?;
/// assert!(meshgnn_geometry::is_watertight(&closed));
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn hull_small_open_parts(
    input: &TriMesh,
    kept: &[u32],
    output: &TriMesh,
    max_kept: usize,
) -> Result<TriMesh> {
    rebuild_small_open_parts(input, kept, output, max_kept, |part| {
        part_hull(input, output, part)
    })
}

/// The surface that replaces an open part: faces over local indices, `i < members.len()`
/// naming the part's output vertex `members[i]` and later ones `extra[i - members.len()]`.
#[derive(Debug, Clone, PartialEq)]
pub struct PartSurface {
    /// The faces, over local indices.
    pub faces: Vec<[u32; 3]>,
    /// Vertices the surface adds, appended to the output's.
    pub extra: Vec<[f32; 3]>,
}

/// The [`convex_hull`] of `part`'s output vertices, unless they lie in one plane or the hull
/// has more than [`MAX_HULL_AREA_RATIO`] times the part's area.
pub fn part_hull(input: &TriMesh, output: &TriMesh, part: &OpenPart) -> Option<PartSurface> {
    let points: Vec<[f32; 3]> = part
        .members
        .iter()
        .map(|&v| output.vertices()[v as usize])
        .collect();
    let hull = convex_hull(&points)?;
    let part_area = surface_area(input.vertices(), part.faces);
    (surface_area(&points, &hull) <= MAX_HULL_AREA_RATIO * part_area).then_some(PartSurface {
        faces: hull,
        extra: Vec::new(),
    })
}

/// `output` with the faces of each small open part (as in [`hull_small_open_parts`]) replaced
/// by `rebuild(part)`, added after the other faces with its extra vertices after the output's
/// (parts in the order of their smallest input vertex); `None` keeps the part's faces.
///
/// Errors as [`hull_small_open_parts`], and when a surface names a local index it lacks.
pub fn rebuild_small_open_parts(
    input: &TriMesh,
    kept: &[u32],
    output: &TriMesh,
    max_kept: usize,
    rebuild: impl Fn(&OpenPart) -> Option<PartSurface>,
) -> Result<TriMesh> {
    if kept.len() > output.vertex_count() {
        return Err(Error::LengthMismatch {
            what: "kept vertices",
            expected: output.vertex_count(),
            actual: kept.len(),
        });
    }
    if let Some((i, &bad)) = kept
        .iter()
        .enumerate()
        .find(|&(_, &v)| v as usize >= input.vertex_count())
    {
        return Err(Error::IndexOutOfRange {
            element: "kept vertex",
            index: i,
            target: "input vertex",
            value: u64::from(bad),
            count: input.vertex_count(),
        });
    }
    let (count, label) = connected_components(input);
    let part_of = |v: u32| -> Option<usize> {
        let l = label[*kept.get(v as usize)? as usize];
        (l != UNREFERENCED).then_some(l as usize)
    };
    let mut members: Vec<Vec<u32>> = vec![Vec::new(); count];
    for v in 0..kept.len() as u32 {
        if let Some(c) = part_of(v) {
            members[c].push(v);
        }
    }
    let sized = |c: usize| (4..=max_kept).contains(&members[c].len());
    if !(0..count).any(sized) {
        return Ok(output.clone());
    }
    // The input faces of the parts of a size to rebuild: whether they close them.
    let mut part_faces: Vec<Vec<[u32; 3]>> = vec![Vec::new(); count];
    for t in input.triangles() {
        let c = label[t[0] as usize] as usize;
        if sized(c) {
            part_faces[c].push(*t);
        }
    }
    let closed: Vec<bool> = part_faces.iter().map(|f| is_closed_surface(f)).collect();
    let small = |c: usize| sized(c) && closed[c];
    // The output faces touching each small part, and whether they close it on their own.
    let mut touching: Vec<Vec<[u32; 3]>> = vec![Vec::new(); count];
    let mut reaches_out = vec![false; count];
    for t in output.triangles() {
        let parts = t.map(part_of);
        for c in parts.iter().flatten().copied().filter(|&c| small(c)) {
            if touching[c].last() != Some(t) {
                touching[c].push(*t);
            }
            reaches_out[c] |= parts.iter().any(|&p| p.is_some_and(|p| p != c));
        }
    }
    let rebuilt: Vec<(usize, PartSurface)> = (0..count)
        .filter(|&c| {
            small(c)
                && (reaches_out[c]
                    || !is_closed_surface(&touching[c])
                    || has_pinched_vertex(&touching[c]))
        })
        .filter_map(|c| {
            let part = OpenPart {
                members: &members[c],
                faces: &part_faces[c],
            };
            rebuild(&part).map(|surface| (c, surface))
        })
        .collect();
    if rebuilt.is_empty() {
        return Ok(output.clone());
    }
    let mut replaced = vec![false; count];
    for &(c, _) in &rebuilt {
        replaced[c] = true;
    }
    let mut vertices = output.vertices().to_vec();
    let mut faces: Vec<[u32; 3]> = output
        .triangles()
        .iter()
        .filter(|t| !t.iter().any(|&v| part_of(v).is_some_and(|c| replaced[c])))
        .copied()
        .collect();
    for (c, surface) in rebuilt {
        let first_extra = vertices.len() as u32;
        let local = |i: u32| -> u32 {
            match members[c].get(i as usize) {
                Some(&v) => v,
                None => first_extra + (i - members[c].len() as u32),
            }
        };
        faces.extend(surface.faces.iter().map(|t| t.map(local)));
        vertices.extend(surface.extra);
    }
    TriMesh::new(vertices, faces)
}

/// The total area of `faces` over `vertices`.
fn surface_area(vertices: &[[f32; 3]], faces: &[[u32; 3]]) -> f64 {
    faces
        .iter()
        .map(|t| 0.5 * norm(triangle_cross(t.map(|v| vertices[v as usize]))))
        .sum()
}

/// True when `faces` is non-empty, no face repeats a corner, and every undirected edge among
/// them has exactly two faces.
fn is_closed_surface(faces: &[[u32; 3]]) -> bool {
    if faces
        .iter()
        .any(|t| t[0] == t[1] || t[1] == t[2] || t[0] == t[2])
    {
        return false;
    }
    let mut edges: Vec<(u32, u32)> = faces
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    edges.sort_unstable();
    !edges.is_empty() && edges.chunk_by(|x, y| x == y).all(|same| same.len() == 2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{icosphere, is_edge_manifold, is_vertex_manifold, is_watertight, torus};

    /// Two unit icospheres, the second shifted by 3 along x.
    fn two_spheres() -> TriMesh {
        let sphere = icosphere(1);
        let n = sphere.vertex_count() as u32;
        TriMesh::new(
            sphere
                .vertices()
                .iter()
                .copied()
                .chain(sphere.vertices().iter().map(|p| [p[0] + 3.0, p[1], p[2]]))
                .collect(),
            sphere
                .triangles()
                .iter()
                .copied()
                .chain(sphere.triangles().iter().map(|t| t.map(|v| v + n)))
                .collect(),
        )
        .unwrap()
    }

    fn kept_positions(input: &TriMesh, kept: &[u32]) -> Vec<[f32; 3]> {
        kept.iter().map(|&v| input.vertices()[v as usize]).collect()
    }

    #[test]
    fn an_open_small_part_becomes_its_hull_and_a_large_one_keeps_its_faces() {
        let input = two_spheres();
        let n = icosphere(1).vertex_count() as u32;
        // Six vertices of the first sphere, eight of the second; one loose face on each.
        let kept: Vec<u32> = (0..6).chain(n..n + 8).collect();
        let output =
            TriMesh::new(kept_positions(&input, &kept), vec![[0, 1, 2], [6, 7, 8]]).unwrap();
        let hulled = hull_small_open_parts(&input, &kept, &output, 6).unwrap();
        // The large part's face first, unchanged, then the first part's hull.
        assert_eq!(hulled.triangles()[0], [6, 7, 8]);
        let hull = &hulled.triangles()[1..];
        assert!(hull.iter().flatten().all(|&v| v < 6));
        assert!(is_watertight(
            &TriMesh::new(hulled.vertices().to_vec(), hull.to_vec()).unwrap()
        ));
        assert_eq!(hulled.vertices(), output.vertices());
    }

    #[test]
    fn a_rebuilt_part_may_add_vertices_after_the_output() {
        let input = two_spheres();
        let kept: Vec<u32> = (0..6).collect();
        let output = TriMesh::new(kept_positions(&input, &kept), vec![[0, 1, 2]]).unwrap();
        // A tetrahedron on members 0, 1, 2 and one new vertex (local index 6).
        let apex = [0.0, 0.0, 5.0];
        let tetrahedron = vec![[0, 2, 1], [0, 1, 6], [1, 2, 6], [2, 0, 6]];
        let rebuilt = rebuild_small_open_parts(&input, &kept, &output, 6, |part| {
            assert_eq!(part.members, &[0, 1, 2, 3, 4, 5]);
            assert_eq!(part.faces.len(), icosphere(1).face_count());
            Some(PartSurface {
                faces: tetrahedron.clone(),
                extra: vec![apex],
            })
        })
        .unwrap();
        assert_eq!(rebuilt.vertex_count(), 7);
        assert_eq!(rebuilt.vertices()[6], apex);
        assert_eq!(rebuilt.triangles(), &tetrahedron[..]);
        // A surface naming a local index past its extras is an error.
        let past = rebuild_small_open_parts(&input, &kept, &output, 6, |_| {
            Some(PartSurface {
                faces: vec![[0, 1, 7]],
                extra: Vec::new(),
            })
        });
        assert!(past.is_err());
    }

    #[test]
    fn a_part_closed_through_a_vertex_of_no_part_is_left_as_it_is() {
        let input = two_spheres();
        // Four kept vertices of the first sphere and a vertex past the kept ones (a hole
        // fill's centre): the tetrahedron over three of them and the centre is closed and
        // reaches no other part.
        let kept = [0u32, 1, 2, 3];
        let mut vertices = kept_positions(&input, &kept);
        vertices.push([0.0, 0.0, 0.0]);
        let faces = vec![[0, 1, 2], [0, 4, 1], [1, 4, 2], [2, 4, 0]];
        let output = TriMesh::new(vertices, faces.clone()).unwrap();
        let asked = std::cell::Cell::new(false);
        let same = rebuild_small_open_parts(&input, &kept, &output, 5, |_| {
            asked.set(true);
            None
        });
        assert_eq!(same.unwrap().triangles(), &faces[..]);
        assert!(!asked.get());
    }

    #[test]
    fn a_part_its_faces_already_close_is_left_as_it_is() {
        let input = two_spheres();
        // Four kept vertices with a closed tetrahedron of faces oriented inwards on purpose:
        // the pass does not touch closed parts, whatever their faces.
        let kept = [0u32, 1, 2, 3];
        let faces = vec![[0, 1, 2], [0, 3, 1], [1, 3, 2], [2, 3, 0]];
        let output = TriMesh::new(kept_positions(&input, &kept), faces.clone()).unwrap();
        let same = hull_small_open_parts(&input, &kept, &output, 5).unwrap();
        assert_eq!(same.triangles(), &faces[..]);
    }

    #[test]
    fn a_part_whose_closed_pieces_touch_at_a_vertex_becomes_its_hull() {
        let input = two_spheres();
        // Seven kept vertices of the first sphere: two closed tetrahedra sharing vertex 3.
        // Every edge has two faces, but vertex 3 carries two fans.
        let kept: Vec<u32> = (0..7).collect();
        let pinched = vec![
            [0, 1, 2],
            [0, 3, 1],
            [1, 3, 2],
            [2, 3, 0],
            [3, 4, 5],
            [3, 6, 4],
            [4, 6, 5],
            [5, 6, 3],
        ];
        let output = TriMesh::new(kept_positions(&input, &kept), pinched).unwrap();
        assert!(is_watertight(&output) && !is_vertex_manifold(&output));
        let hulled = hull_small_open_parts(&input, &kept, &output, 7).unwrap();
        assert!(is_watertight(&hulled) && is_vertex_manifold(&hulled));
        let used: std::collections::BTreeSet<u32> =
            hulled.triangles().iter().flatten().copied().collect();
        assert_eq!(used.len(), 7, "every kept vertex on the hull");
    }

    #[test]
    fn a_face_bridging_two_parts_is_dropped_and_open_input_parts_are_left() {
        let input = two_spheres();
        let n = icosphere(1).vertex_count() as u32;
        let kept = [0u32, 1, 2, 3, 4, n];
        let output = TriMesh::new(kept_positions(&input, &kept), vec![[0, 1, 5]]).unwrap();
        let hulled = hull_small_open_parts(&input, &kept, &output, 5).unwrap();
        assert!(hulled.triangles().iter().flatten().all(|&v| v < 5));
        assert!(is_watertight(&hulled) && is_edge_manifold(&hulled));
        // The same vertices on an open input (the first sphere without one face) stay.
        let open =
            TriMesh::new(input.vertices().to_vec(), input.triangles()[1..].to_vec()).unwrap();
        let left = hull_small_open_parts(&open, &kept, &output, 5).unwrap();
        assert_eq!(left.triangles(), output.triangles());
    }

    #[test]
    fn parts_outside_the_size_window_and_flat_parts_keep_their_faces() {
        let input = two_spheres();
        let kept = [0u32, 1, 2, 3, 4, 5];
        let output = TriMesh::new(kept_positions(&input, &kept), vec![[0, 1, 2]]).unwrap();
        // Six kept vertices, at most five hulled.
        let same = hull_small_open_parts(&input, &kept, &output, 5).unwrap();
        assert_eq!(same.triangles(), output.triangles());
        // Four kept vertices in one plane.
        let flat = TriMesh::new(
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [1.0, 1.0, 0.0],
            ],
            vec![[0, 1, 2]],
        )
        .unwrap();
        let same = hull_small_open_parts(&input, &[0, 1, 2, 3], &flat, 5).unwrap();
        assert_eq!(same.triangles(), flat.triangles());
    }

    #[test]
    fn a_curled_part_whose_hull_would_span_its_curl_keeps_its_faces() {
        // A thin ring (area 4π²·0.05 ≈ 2.0) kept at five vertices around it, outer and upper
        // ones mixed so they are not coplanar: their hull is a pentagonal slab of about
        // 2 · 2.4 = 4.8, more than twice the ring's area.
        let ring = torus(1.0, 0.05, 40, 8);
        let kept = [0u32, 8 * 8 + 2, 16 * 8, 24 * 8 + 2, 32 * 8];
        let output = TriMesh::new(kept_positions(&ring, &kept), vec![[0, 1, 2]]).unwrap();
        let same = hull_small_open_parts(&ring, &kept, &output, 5).unwrap();
        assert_eq!(same.triangles(), output.triangles());
        // A fat ring (tube 0.6, area ≈ 23.7) with the same choice is hulled.
        let fat = torus(1.0, 0.6, 40, 8);
        let output = TriMesh::new(kept_positions(&fat, &kept), vec![[0, 1, 2]]).unwrap();
        let hulled = hull_small_open_parts(&fat, &kept, &output, 5).unwrap();
        assert!(is_watertight(&hulled));
    }

    #[test]
    fn kept_lists_that_do_not_fit_are_errors() {
        let input = two_spheres();
        let output = TriMesh::new(vec![[0.0; 3]; 2], vec![]).unwrap();
        assert!(hull_small_open_parts(&input, &[0, 1, 2], &output, 5).is_err());
        assert!(hull_small_open_parts(&input, &[0, 99_999], &output, 5).is_err());
    }
}
