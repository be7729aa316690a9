//! Collapses that QEM's geometric checks refuse, for [`super::kept_vertex_connectivity`]:
//! on a part that curls (the data-fixtures ant's antennae), the flip and fold checks of
//! Garland & Heckbert (1997, §3) hold back vertices a closed surface over the kept ones does
//! not need. Here only the link condition (Dey et al., 1999) guards a collapse, so the
//! surface stays a closed 2-manifold while a face may fold; the least folding collapse goes
//! first (docs/mesh_simplifier_model.md, "Curled parts folded closed").

use meshgnn_geometry::vec3::{dot, norm, triangle_cross};

/// The surface `faces` over `positions` with held vertices (`held[v]`) collapsed onto a
/// neighbour, one at a time, until at most `max_held` remain or no collapse keeps the link
/// condition: the common neighbours of the two ends are the apexes of the faces on their edge,
/// no interior edge joins two border vertices, and the part keeps more than four vertices. Of
/// the collapses allowed, each step takes the one whose moved faces keep their normals best
/// (the smallest worst turn). Vertex numbers are unchanged; a collapsed vertex loses its
/// faces and its `held` mark.
pub(crate) fn fold_held_vertices(
    positions: &[[f32; 3]],
    faces: &mut Vec<[u32; 3]>,
    held: &mut [bool],
    max_held: usize,
) {
    let mut surface = Surface::new(positions.len(), std::mem::take(faces));
    let mut live = (0..positions.len() as u32)
        .filter(|&v| !surface.fan(v).is_empty())
        .count();
    let mut held_live: Vec<u32> = (0..held.len() as u32)
        .filter(|&v| held[v as usize] && !surface.fan(v).is_empty())
        .collect();
    while held_live.len() > max_held && live > 4 {
        let best = held_live
            .iter()
            .flat_map(|&h| surface.neighbours(h).into_iter().map(move |t| (h, t)))
            .filter(|&(h, t)| surface.link_condition_holds(h, t))
            .map(|(h, t)| (surface.worst_normal_cos(positions, h, t), h, t))
            .max_by(|a, b| a.0.total_cmp(&b.0).then(b.1.cmp(&a.1)).then(b.2.cmp(&a.2)));
        let Some((_, h, t)) = best else { break };
        surface.collapse(h, t);
        held[h as usize] = false;
        held_live.retain(|&v| v != h);
        live -= 1;
    }
    *faces = surface.into_faces();
}

/// A small triangle surface with the faces around each vertex, for collapses.
struct Surface {
    faces: Vec<[u32; 3]>,
    alive: Vec<bool>,
    /// Per vertex, its live faces.
    fans: Vec<Vec<u32>>,
}

impl Surface {
    fn new(vertex_count: usize, faces: Vec<[u32; 3]>) -> Self {
        let mut fans = vec![Vec::new(); vertex_count];
        for (f, t) in faces.iter().enumerate() {
            for &v in t {
                fans[v as usize].push(f as u32);
            }
        }
        Self {
            alive: vec![true; faces.len()],
            faces,
            fans,
        }
    }

    /// The live faces around `v`.
    fn fan(&self, v: u32) -> &[u32] {
        &self.fans[v as usize]
    }

    /// The vertices sharing a face with `v`, ascending.
    fn neighbours(&self, v: u32) -> Vec<u32> {
        let mut ring: Vec<u32> = self
            .fan(v)
            .iter()
            .flat_map(|&f| self.faces[f as usize])
            .filter(|&u| u != v)
            .collect();
        ring.sort_unstable();
        ring.dedup();
        ring
    }

    /// The live faces holding both `a` and `b`.
    fn edge_faces(&self, a: u32, b: u32) -> impl Iterator<Item = [u32; 3]> + '_ {
        self.fan(a)
            .iter()
            .map(|&f| self.faces[f as usize])
            .filter(move |t| t.contains(&b))
    }

    /// Whether `v` lies on an edge with one face.
    fn on_border(&self, v: u32) -> bool {
        self.neighbours(v)
            .into_iter()
            .any(|u| self.edge_faces(v, u).count() == 1)
    }

    /// The link condition for collapsing the edge `(a, b)` of a 2-manifold: every common
    /// neighbour is the apex of a face on the edge, and the edge is on the border if both
    /// ends are.
    fn link_condition_holds(&self, a: u32, b: u32) -> bool {
        let ring_b = self.neighbours(b);
        let apexes: Vec<u32> = self
            .edge_faces(a, b)
            .flatten()
            .filter(|&v| v != a && v != b)
            .collect();
        let common_are_apexes = self
            .neighbours(a)
            .into_iter()
            .filter(|v| ring_b.contains(v))
            .all(|v| apexes.contains(&v));
        let border_edge = apexes.len() == 1;
        common_are_apexes && (border_edge || !(self.on_border(a) && self.on_border(b)))
    }

    /// The smallest cosine between a face's normal before and after `h` moves onto `t`, over
    /// the faces of `h` that survive the collapse; −1 for a face that becomes degenerate.
    fn worst_normal_cos(&self, positions: &[[f32; 3]], h: u32, t: u32) -> f64 {
        let corners = |f: [u32; 3]| f.map(|v| positions[v as usize]);
        self.fan(h)
            .iter()
            .map(|&f| self.faces[f as usize])
            .filter(|f| !f.contains(&t))
            .map(|f| {
                let before = triangle_cross(corners(f));
                let after = triangle_cross(corners(f.map(|v| if v == h { t } else { v })));
                let scale = norm(before) * norm(after);
                if scale > 0.0 {
                    dot(before, after) / scale
                } else {
                    -1.0
                }
            })
            .fold(1.0, f64::min)
    }

    /// Moves `h` onto `t`: the faces on the edge die, the others of `h` become `t`'s.
    fn collapse(&mut self, h: u32, t: u32) {
        for f in std::mem::take(&mut self.fans[h as usize]) {
            let face = &mut self.faces[f as usize];
            if face.contains(&t) {
                self.alive[f as usize] = false;
                for v in *face {
                    if v != h {
                        self.fans[v as usize].retain(|&g| g != f);
                    }
                }
            } else {
                for v in face.iter_mut() {
                    if *v == h {
                        *v = t;
                    }
                }
                self.fans[t as usize].push(f);
            }
        }
    }

    /// The live faces, in their input order.
    fn into_faces(self) -> Vec<[u32; 3]> {
        self.faces
            .into_iter()
            .zip(self.alive)
            .filter_map(|(t, alive)| alive.then_some(t))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A triangular bipyramid: apexes 0 and 1, equator 2, 3, 4.
    const BIPYRAMID: [[u32; 3]; 6] = [
        [0, 2, 3],
        [0, 3, 4],
        [0, 4, 2],
        [1, 3, 2],
        [1, 4, 3],
        [1, 2, 4],
    ];
    use meshgnn_geometry::{
        TriMesh, icosphere, is_edge_manifold, is_vertex_manifold, is_watertight,
    };

    #[test]
    fn held_vertices_fold_down_to_the_bound_and_the_sphere_stays_closed() {
        let sphere = icosphere(1); // 42 vertices, 80 faces
        let mut faces = sphere.triangles().to_vec();
        // Every vertex but the first four is held.
        let mut held: Vec<bool> = (0..42).map(|v| v >= 4).collect();
        fold_held_vertices(sphere.vertices(), &mut faces, &mut held, 3);
        assert_eq!(held.iter().filter(|&&h| h).count(), 3);
        // A closed genus-0 surface over 4 + 3 vertices has 2 · 7 − 4 faces.
        assert_eq!(faces.len(), 10);
        let folded = TriMesh::new(sphere.vertices().to_vec(), faces).unwrap();
        assert!(is_watertight(&folded) && is_edge_manifold(&folded));
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(32))]
        /// Any held vertices of a noisy sphere, any bound: the surface stays closed and a
        /// 2-manifold (each edge two faces, each vertex one fan), the genus-0 count of faces
        /// holds, kept vertices all stay, and held ones go down to the bound or to four
        /// vertices in all.
        #[test]
        fn folding_keeps_a_closed_two_manifold(
            stride in 2usize..80,
            salt in 0u32..1000,
            max_held in 0usize..30,
            noise in 0.0f32..0.4,
        ) {
            let sphere = icosphere(2); // 162 vertices
            let positions: Vec<[f32; 3]> = sphere
                .vertices()
                .iter()
                .enumerate()
                .map(|(i, p)| {
                    let wobble = ((i as u32).wrapping_mul(2_654_435_761) ^ salt) % 1000;
                    let wobble = wobble as f32 / 1000.0;
                    p.map(|x| x * (1.0 + noise * (wobble - 0.5)))
                })
                .collect();
            let mut faces = sphere.triangles().to_vec();
            let mut held: Vec<bool> = (0..162usize)
                .map(|v| !(v + salt as usize).is_multiple_of(stride))
                .collect();
            let kept: Vec<usize> = (0..162).filter(|&v| !held[v]).collect();
            fold_held_vertices(&positions, &mut faces, &mut held, max_held);
            let folded = TriMesh::new(positions, faces).unwrap();
            proptest::prop_assert!(is_watertight(&folded) && is_edge_manifold(&folded));
            proptest::prop_assert!(is_vertex_manifold(&folded));
            let mut used = [false; 162];
            for &v in folded.triangles().iter().flatten() {
                used[v as usize] = true;
            }
            let live = used.iter().filter(|&&u| u).count();
            proptest::prop_assert_eq!(folded.face_count(), 2 * live - 4);
            proptest::prop_assert!(kept.iter().all(|&v| used[v]));
            let held_left = (0..162).filter(|&v| held[v] && used[v]).count();
            proptest::prop_assert!(held_left <= max_held || live == 4);
            // A vertex no longer used is no longer held.
            proptest::prop_assert!((0..162).all(|v| used[v] || !held[v]));
        }
    }

    #[test]
    fn a_pinching_collapse_loses_to_one_that_turns_faces_more() {
        // The bipyramid with 3 just beside 2:
        // moving 3 onto 2 turns no face much, but 2 and 3 share a third neighbour, 4, so it
        // would leave two faces on one triangle. Only the collapses onto an apex are allowed.
        let positions = vec![
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
            [1.0, 0.0, 0.0],
            [0.95, 0.3, 0.0],
            [-0.5, -0.8, 0.0],
        ];
        let mut faces = BIPYRAMID.to_vec();
        let mut held = vec![false, false, false, true, false];
        fold_held_vertices(&positions, &mut faces, &mut held, 0);
        assert_eq!(faces.len(), 4);
        let tetrahedron = TriMesh::new(positions, faces).unwrap();
        assert!(is_watertight(&tetrahedron) && is_edge_manifold(&tetrahedron));
        assert!(!held[3]);
    }

    #[test]
    fn a_tetrahedron_is_left_whole() {
        let sphere = icosphere(1);
        let mut faces = sphere.triangles().to_vec();
        let mut held = vec![true; 42];
        fold_held_vertices(sphere.vertices(), &mut faces, &mut held, 0);
        // Four vertices are the fewest a closed surface has.
        assert_eq!(faces.len(), 4);
        assert_eq!(held.iter().filter(|&&h| h).count(), 4);
    }

    #[test]
    fn the_link_condition_refuses_a_collapse_that_pinches() {
        // Equator edge (2, 3): common neighbours 0 and 1 (its apexes) and 4, which is not:
        // collapsing it would pinch the surface into two sheets along (survivor, 4).
        let surface = Surface::new(5, BIPYRAMID.to_vec());
        assert!(!surface.link_condition_holds(2, 3));
        // Apex-to-equator edge (0, 2): common neighbours 3 and 4, its apexes.
        assert!(surface.link_condition_holds(0, 2));
    }
}
