//! Turns scored, unoriented candidate triangles into an edge-manifold, oriented face set: the
//! final pass of the neural mesh simplifier (thesis ch. 6.4 keeps the faces with probability
//! above 0.5 and, per edge, the two most probable; the orientation pass goes beyond the
//! thesis, whose candidates carry no orientation).
//!
//! 1. Candidates above the threshold, most probable first (ties by index), are accepted while
//!    each of their three edges has fewer than two accepted faces; triangles with a repeated
//!    corner are dropped.
//! 2. Orientation propagates face to face across shared edges (breadth first, lowest face
//!    index first: a neighbour is flipped when it runs the shared edge the same way), so every
//!    edge is run once each way. A non-orientable component (a Möbius strip) keeps one
//!    inconsistent edge; it stays edge-manifold.
//! 3. Each connected component is then flipped as a whole when it faces away from the
//!    reference normals (the input's vertex normals at the corners: the sum over its faces of
//!    the area normal dotted with the sum of the corners' normals is negative), or, without
//!    them, when its flux around its centroid is negative (a closed component then faces
//!    outwards). A face folded back over its neighbours stays consistent with them, so it
//!    faces against its own corners' normals: the fold is in the connectivity, and
//!    [`crate::flip_folds`] mends it there. Turning each face along its corners' normals
//!    instead, as this pass did before, runs an edge twice the same way at every fold and
//!    across thin parts, whose two sides' normals meet in one face
//!    (docs/mesh_simplifier_model.md, "One orientation per part").

use std::collections::HashMap;
use std::collections::VecDeque;

use crate::cap_flips::edge_key;
use crate::error::{Error, Result};
use crate::vec3::{dot, sub, to_f64, triangle_cross};

/// The accepted faces, oriented, in acceptance order (most probable first).
///
/// Errors when the lengths disagree, a corner is out of range, or the threshold or a
/// probability is NaN.
///
/// ```
/// use meshgnn_geometry::select_manifold_faces;
/// let v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 1.0, 1.0]];
/// // Three faces on the edge (0, 1): only the two most probable are kept.
/// let t = [[0, 1, 2], [0, 1, 3], [0, 1, 4]];
/// let kept = select_manifold_faces(&v, &t, &[0.9, 0.8, 0.7], 0.5, None)?;
/// assert_eq!(kept.len(), 2);
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn select_manifold_faces(
    vertices: &[[f32; 3]],
    triangles: &[[u32; 3]],
    probabilities: &[f32],
    threshold: f32,
    reference_normals: Option<&[[f32; 3]]>,
) -> Result<Vec<[u32; 3]>> {
    if probabilities.len() != triangles.len() {
        return Err(Error::LengthMismatch {
            what: "face probabilities",
            expected: triangles.len(),
            actual: probabilities.len(),
        });
    }
    if let Some(normals) = reference_normals
        && normals.len() != vertices.len()
    {
        return Err(Error::LengthMismatch {
            what: "reference normals",
            expected: vertices.len(),
            actual: normals.len(),
        });
    }
    if threshold.is_nan() || probabilities.iter().any(|p| p.is_nan()) {
        return Err(Error::InvalidParameter {
            name: "face probabilities",
            message: "NaN threshold or probability".into(),
        });
    }
    if let Some((f, &bad)) = triangles
        .iter()
        .enumerate()
        .flat_map(|(f, t)| t.iter().map(move |v| (f, v)))
        .find(|&(_, &v)| v as usize >= vertices.len())
    {
        return Err(Error::IndexOutOfRange {
            element: "triangle",
            index: f,
            target: "vertex",
            value: u64::from(bad),
            count: vertices.len(),
        });
    }
    let mut order: Vec<usize> = (0..triangles.len())
        .filter(|&f| probabilities[f] > threshold)
        .collect();
    order.sort_by(|&a, &b| {
        probabilities[b]
            .total_cmp(&probabilities[a])
            .then(a.cmp(&b))
    });
    let mut uses: HashMap<(u32, u32), u8> = HashMap::new();
    let mut faces = Vec::new();
    for f in order {
        let [a, b, c] = triangles[f];
        if a == b || b == c || a == c {
            continue;
        }
        let edges = [edge_key(a, b), edge_key(b, c), edge_key(c, a)];
        if edges.iter().all(|e| uses.get(e).copied().unwrap_or(0) < 2) {
            for e in edges {
                *uses.entry(e).or_insert(0) += 1;
            }
            faces.push([a, b, c]);
        }
    }
    match reference_normals {
        Some(normals) => orient_consistently(&mut faces, |faces, component| {
            reference_agreement(vertices, normals, faces, component)
        }),
        None => orient_consistently(&mut faces, |faces, component| {
            outward_flux(vertices, faces, component)
        }),
    }
    Ok(faces)
}

/// The directed edges of `t`.
fn edges_of(t: [u32; 3]) -> [(u32, u32); 3] {
    [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])]
}

/// True when `t` runs the directed edge `a → b`.
fn runs(t: [u32; 3], a: u32, b: u32) -> bool {
    edges_of(t).contains(&(a, b))
}

/// The faces on each undirected edge.
fn faces_by_edge(faces: &[[u32; 3]]) -> HashMap<(u32, u32), Vec<usize>> {
    let mut by_edge: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
    for (f, &t) in faces.iter().enumerate() {
        for (a, b) in edges_of(t) {
            by_edge.entry(edge_key(a, b)).or_default().push(f);
        }
    }
    by_edge
}

/// Steps 2 and 3 of the module docs on edge-manifold `faces`: orientation propagated within
/// each connected component, the component flipped as a whole when `facing` of it is negative.
fn orient_consistently(faces: &mut [[u32; 3]], facing: impl Fn(&[[u32; 3]], &[usize]) -> f64) {
    let by_edge = faces_by_edge(faces);
    let mut visited = vec![false; faces.len()];
    for seed in 0..faces.len() {
        if visited[seed] {
            continue;
        }
        visited[seed] = true;
        let mut component = vec![seed];
        let mut queue = VecDeque::from([seed]);
        while let Some(f) = queue.pop_front() {
            let t = faces[f];
            for (a, b) in edges_of(t) {
                let Some(others) = by_edge.get(&edge_key(a, b)) else {
                    continue;
                };
                for &g in others {
                    if visited[g] {
                        continue;
                    }
                    if runs(faces[g], a, b) {
                        faces[g].swap(1, 2);
                    }
                    visited[g] = true;
                    component.push(g);
                    queue.push_back(g);
                }
            }
        }
        if facing(faces, &component) < 0.0 {
            for &f in &component {
                faces[f].swap(1, 2);
            }
        }
    }
}

/// How well the component faces along the reference normals: the sum over its faces of the
/// area normal dotted with the sum of the corners' normals.
fn reference_agreement(
    vertices: &[[f32; 3]],
    normals: &[[f32; 3]],
    faces: &[[u32; 3]],
    component: &[usize],
) -> f64 {
    component
        .iter()
        .map(|&f| {
            dot(
                triangle_cross(faces[f].map(|v| vertices[v as usize])),
                reference_normal(normals, faces[f]),
            )
        })
        .sum()
}

/// The sum of the reference normals at `t`'s corners.
pub(crate) fn reference_normal(normals: &[[f32; 3]], t: [u32; 3]) -> [f64; 3] {
    t.iter()
        .map(|&v| to_f64(normals[v as usize]))
        .fold([0.0; 3], |s, x| [s[0] + x[0], s[1] + x[1], s[2] + x[2]])
}

/// The component's flux around its centroid: positive when a closed one faces outwards.
fn outward_flux(vertices: &[[f32; 3]], faces: &[[u32; 3]], component: &[usize]) -> f64 {
    let corners = |f: usize| faces[f].map(|v| vertices[v as usize]);
    let count = (component.len() * 3) as f64;
    let mut centre = [0.0; 3];
    for &f in component {
        for p in corners(f) {
            for d in 0..3 {
                centre[d] += f64::from(p[d]) / count;
            }
        }
    }
    component
        .iter()
        .map(|&f| {
            let c = corners(f).map(to_f64);
            let mid = [0, 1, 2].map(|d| (c[0][d] + c[1][d] + c[2][d]) / 3.0);
            dot(sub(mid, centre), triangle_cross(corners(f)))
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{TriMesh, icosphere, is_edge_manifold, is_watertight, vertex_normals};

    /// Every directed edge at most once: consistently oriented.
    fn consistently_oriented(faces: &[[u32; 3]]) -> bool {
        let mut seen = std::collections::HashSet::new();
        faces
            .iter()
            .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .all(|e| seen.insert(e))
    }

    fn signed_volume(v: &[[f32; 3]], faces: &[[u32; 3]]) -> f64 {
        faces
            .iter()
            .map(|t| {
                let c = t.map(|i| to_f64(v[i as usize]));
                dot(c[0], crate::vec3::cross(c[1], c[2])) / 6.0
            })
            .sum()
    }

    #[test]
    fn scrambled_sphere_with_fins_comes_back_whole_and_outward() {
        let sphere = icosphere(2);
        let v = sphere.vertices().to_vec();
        // Faces flipped at random-looking places, plus a lower-scored fin on every 7th edge
        // and low-probability noise.
        let mut triangles: Vec<[u32; 3]> = Vec::new();
        let mut probabilities = Vec::new();
        for (f, t) in sphere.triangles().iter().enumerate() {
            let t = if f % 3 == 0 { [t[0], t[2], t[1]] } else { *t };
            triangles.push(t);
            probabilities.push(0.9 - (f % 5) as f32 * 0.01);
            if f % 7 == 0 {
                triangles.push([t[0], t[1], (t[2] + 17) % 162]);
                probabilities.push(0.6);
            }
            if f % 11 == 0 {
                triangles.push([t[0], (t[1] + 40) % 162, (t[2] + 80) % 162]);
                probabilities.push(0.3);
            }
        }
        for normals in [None, Some(vertex_normals(&sphere))] {
            let kept =
                select_manifold_faces(&v, &triangles, &probabilities, 0.5, normals.as_deref())
                    .unwrap();
            let mesh = TriMesh::new(v.clone(), kept.clone()).unwrap();
            assert!(is_edge_manifold(&mesh));
            assert!(consistently_oriented(&kept));
            assert!(signed_volume(&v, &kept) > 0.0, "faces point inwards");
            let mut sorted: Vec<[u32; 3]> = kept
                .iter()
                .map(|t| {
                    let mut t = *t;
                    t.sort_unstable();
                    t
                })
                .collect();
            sorted.sort_unstable();
            let mut want: Vec<[u32; 3]> = sphere
                .triangles()
                .iter()
                .map(|t| {
                    let mut t = *t;
                    t.sort_unstable();
                    t
                })
                .collect();
            want.sort_unstable();
            // Every fin lost to the two sphere faces of its edge, noise fell below 0.5.
            assert_eq!(sorted, want);
            assert!(is_watertight(&mesh));
        }
    }

    /// The z component of each face's area normal over `v`.
    fn normal_z(v: &[[f32; 3]], faces: &[[u32; 3]]) -> Vec<f64> {
        faces
            .iter()
            .map(|f| triangle_cross(f.map(|i| v[i as usize]))[2])
            .collect()
    }

    #[test]
    fn with_reference_normals_a_fold_stays_consistent_and_the_part_faces_them() {
        // Two faces of a unit square, and a third on the edge (1, 3) folded back over the
        // second (its apex inside the square): consistent with its neighbour it faces −z.
        let v = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.5, 0.6, 0.0],
        ];
        let t = [[0, 2, 1], [1, 2, 3], [1, 3, 4]];
        for (reference, square_z) in [([0.0, 0.0, 1.0], 1.0), ([0.0, 0.0, -1.0], -1.0)] {
            let normals = [reference; 5];
            let kept =
                select_manifold_faces(&v, &t, &[0.9, 0.8, 0.7], 0.5, Some(&normals)).unwrap();
            assert!(consistently_oriented(&kept), "{kept:?}");
            let z = normal_z(&v, &kept);
            // The square faces the references, the fold against them.
            assert!(z[0] * square_z > 0.0 && z[1] * square_z > 0.0, "{kept:?}");
            assert!(z[2] * square_z < 0.0, "{kept:?}");
        }
    }

    #[test]
    fn a_thin_part_whose_sides_meet_in_one_strip_is_oriented_as_one() {
        // A strip of four faces across the edge of a thin plate: the corners of the first
        // two carry the top side's normal (+z), those of the last two the bottom's (−z), and
        // the middle edge's ends both. Turned one by one, the faces would run the middle
        // edges the same way; the strip is one part, facing the side its larger faces see.
        let v = [
            [0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [1.5, 0.0, 0.0],
            [1.5, 1.0, 0.0],
        ];
        let t = [[0, 2, 1], [1, 2, 3], [2, 4, 3], [3, 4, 5]];
        let up = [0.0, 0.0, 1.0];
        let down = [0.0, 0.0, -1.0];
        let normals = [up, up, [0.0; 3], [0.0; 3], down, down];
        let kept = select_manifold_faces(&v, &t, &[0.9; 4], 0.5, Some(&normals)).unwrap();
        assert!(consistently_oriented(&kept), "{kept:?}");
        assert!(normal_z(&v, &kept).iter().all(|&z| z > 0.0), "{kept:?}");
        // Without the references the same faces propagate the same way (flux decides the side).
        let propagated = select_manifold_faces(&v, &t, &[0.9; 4], 0.5, None).unwrap();
        assert!(consistently_oriented(&propagated));
    }

    #[test]
    fn a_cap_follows_its_neighbours_not_its_noisy_normal_and_then_flips_away() {
        // Unit square: B below the diagonal AC, a fan from D above it, and M on the diagonal
        // (1.2·10⁻⁷ below it after f32 rounding): cap A C M, consistent with its neighbours,
        // would face −z by its own normal.
        let v = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.5, 0.499_999_88, 0.0],
        ];
        assert!(triangle_cross([v[0], v[2], v[4]])[2] < 0.0);
        let t = [[0, 1, 2], [0, 4, 2], [0, 4, 3], [4, 2, 3]];
        let up = [[0.0, 0.0, 1.0]; 5];
        let kept = select_manifold_faces(&v, &t, &[0.9; 4], 0.5, Some(&up)).unwrap();
        assert!(consistently_oriented(&kept), "{kept:?}");
        let flipped = crate::flip_caps(&TriMesh::new(v.to_vec(), kept).unwrap()).unwrap();
        let areas = crate::face_areas(&flipped);
        assert!(areas.iter().all(|&a| a > 0.1), "{areas:?}");
        assert!((areas.iter().sum::<f64>() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn bad_inputs_are_errors() {
        let v = [[0.0f32; 3]; 3];
        assert!(select_manifold_faces(&v, &[[0, 1, 2]], &[], 0.5, None).is_err());
        assert!(select_manifold_faces(&v, &[[0, 1, 5]], &[0.9], 0.5, None).is_err());
        assert!(select_manifold_faces(&v, &[[0, 1, 2]], &[f32::NAN], 0.5, None).is_err());
        assert!(
            select_manifold_faces(&v, &[[0, 0, 2]], &[0.9], 0.5, None)
                .unwrap()
                .is_empty()
        );
    }
}
