//! The convex hull of a small point set as an outward-facing closed triangle mesh: the shape
//! the neural mesh simplifier gives a closed part it kept too few vertices of to mesh
//! ([`crate::hull_small_open_parts`]).
//!
//! Incremental (the beneath-beyond method): a tetrahedron of four extreme points, then each
//! further point, in index order, replaces the faces it sees by a fan from their horizon to
//! itself. O(n · F), fine for the tens of points it is meant for. A point within a relative
//! `1e-6` of the bounding-box diagonal from a face's plane counts as behind it, so nearly
//! coplanar points do not make slivers and the hull never uses a point twice.

use crate::bounding_box::bounding_box_diagonal;
use crate::vec3::{cross, dot, norm, sub, to_f64};

/// Distance below which a point counts as on a plane, line or point, relative to the
/// bounding-box diagonal.
const RELATIVE_TOLERANCE: f64 = 1e-6;

/// The hull's faces, indices into `points`, each counter-clockwise seen from outside (its
/// normal `(b − a) × (c − a)` points out); every edge is shared by exactly two faces.
/// Points inside the hull or on its faces are left out. `None` for fewer than four points
/// or points that all lie in one plane (within the tolerance of the module docs).
///
/// ```
/// use meshgnn_geometry::convex_hull;
/// // The corners of a tetrahedron and a point inside it.
/// let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.1, 0.1, 0.1]];
/// let hull = convex_hull(&p).unwrap();
/// assert_eq!(hull.len(), 4);
/// assert!(hull.iter().all(|t| !t.contains(&4)));
/// assert!(convex_hull(&p[..3]).is_none());
/// ```
pub fn convex_hull(points: &[[f32; 3]]) -> Option<Vec<[u32; 3]>> {
    let p: Vec<[f64; 3]> = points.iter().map(|&x| to_f64(x)).collect();
    let tolerance = RELATIVE_TOLERANCE * bounding_box_diagonal(points);
    let [a, b, c, d] = initial_tetrahedron(&p, tolerance)?;
    let mut faces = vec![[a, b, c], [a, d, b], [b, d, c], [c, d, a]];
    if signed_distance(&p, [a, b, c], p[d as usize]) > 0.0 {
        faces.iter_mut().for_each(|t| t.swap(1, 2));
    }
    for q in 0..p.len() as u32 {
        if [a, b, c, d].contains(&q) {
            continue;
        }
        let (seen, kept): (Vec<[u32; 3]>, Vec<[u32; 3]>) = faces
            .into_iter()
            .partition(|&t| signed_distance(&p, t, p[q as usize]) > tolerance);
        faces = kept;
        // The horizon: the directed edges of seen faces whose reverse no seen face runs.
        let runs_seen = |x: u32, y: u32| seen.iter().any(|t| directed_edges(*t).contains(&(x, y)));
        for t in &seen {
            for (x, y) in directed_edges(*t) {
                if !runs_seen(y, x) {
                    faces.push([x, y, q]);
                }
            }
        }
    }
    Some(faces)
}

/// Four points spanning a solid: the lowest (lexicographically), the farthest from it, the
/// farthest from their line, the farthest from their plane; `None` where one of those
/// distances is within `tolerance`.
fn initial_tetrahedron(p: &[[f64; 3]], tolerance: f64) -> Option<[u32; 4]> {
    let farthest =
        |distance: &dyn Fn([f64; 3]) -> f64| {
            (0..p.len()).map(|i| (distance(p[i]), i as u32)).fold(
                (f64::NEG_INFINITY, 0),
                |best, x| if x.0 > best.0 { x } else { best },
            )
        };
    let a = (0..p.len())
        .min_by(|&i, &j| p[i].partial_cmp(&p[j]).unwrap_or(std::cmp::Ordering::Equal))?
        as u32;
    let pa = p[a as usize];
    let (ab, b) = farthest(&|x| norm(sub(x, pa)));
    if ab <= tolerance {
        return None;
    }
    let axis = sub(p[b as usize], pa);
    let (line, c) = farthest(&|x| norm(cross(axis, sub(x, pa))) / ab);
    if line <= tolerance {
        return None;
    }
    let (plane, d) = farthest(&|x| signed_distance(p, [a, b, c], x).abs());
    (plane > tolerance).then_some([a, b, c, d])
}

/// Distance of `x` from the plane of `t`, positive on the side its normal points to.
fn signed_distance(p: &[[f64; 3]], t: [u32; 3], x: [f64; 3]) -> f64 {
    let [a, b, c] = t.map(|i| p[i as usize]);
    let normal = cross(sub(b, a), sub(c, a));
    dot(normal, sub(x, a)) / norm(normal)
}

/// The directed edges of `t`.
fn directed_edges(t: [u32; 3]) -> [(u32, u32); 3] {
    [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])]
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::collections::HashMap;

    /// Every directed edge once and its reverse once: closed and consistently oriented.
    fn assert_closed_and_oriented(faces: &[[u32; 3]]) {
        let mut runs: HashMap<(u32, u32), usize> = HashMap::new();
        for &t in faces {
            for e in directed_edges(t) {
                *runs.entry(e).or_default() += 1;
            }
        }
        for (&(x, y), &n) in &runs {
            assert_eq!(n, 1, "edge {x}→{y} run {n} times");
            assert_eq!(runs.get(&(y, x)), Some(&1), "edge {x}→{y} has no twin");
        }
    }

    fn volume(points: &[[f32; 3]], faces: &[[u32; 3]]) -> f64 {
        faces
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| to_f64(points[i as usize]));
                dot(a, cross(b, c)) / 6.0
            })
            .sum()
    }

    #[test]
    fn the_cube_has_twelve_outward_faces_and_leaves_its_centre_out() {
        let mut points: Vec<[f32; 3]> = (0..8)
            .map(|i| [(i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32])
            .collect();
        points.push([0.5, 0.5, 0.5]);
        // A point on a face's plane is not a corner either.
        points.push([0.5, 0.5, 1.0]);
        let faces = convex_hull(&points).unwrap();
        assert_eq!(faces.len(), 12);
        assert!(faces.iter().all(|t| t.iter().all(|&v| v < 8)));
        assert_closed_and_oriented(&faces);
        assert!((volume(&points, &faces) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn the_octahedron_encloses_four_thirds() {
        let points = [
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
        ];
        let faces = convex_hull(&points).unwrap();
        assert_eq!(faces.len(), 8);
        assert_closed_and_oriented(&faces);
        assert!((volume(&points, &faces) - 4.0 / 3.0).abs() < 1e-12);
    }

    #[test]
    fn flat_collinear_repeated_and_too_few_points_have_no_hull() {
        let square = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
        ];
        assert!(convex_hull(&square).is_none());
        let line = [
            [0.0, 0.0, 0.0],
            [1.0, 1.0, 1.0],
            [2.0, 2.0, 2.0],
            [3.0, 3.0, 3.0],
        ];
        assert!(convex_hull(&line).is_none());
        assert!(convex_hull(&[[1.0, 2.0, 3.0]; 6]).is_none());
        assert!(convex_hull(&square[..3]).is_none());
        assert!(convex_hull(&[]).is_none());
        // Flat to within the tolerance: a bump of 1e-8 on a unit square.
        let mut bumped = square.to_vec();
        bumped.push([0.5, 0.5, 1e-8]);
        assert!(convex_hull(&bumped).is_none());
    }

    proptest! {
        #[test]
        fn every_point_lies_behind_every_face_of_a_closed_hull(
            points in prop::collection::vec(prop::array::uniform3(-10.0f32..10.0), 4..40)
        ) {
            check_hull(&points)?;
        }

        /// Small integer grids: many points on one face, on one edge, repeated.
        #[test]
        fn grid_points_with_coplanar_and_repeated_points_give_a_closed_hull(
            points in prop::collection::vec(prop::array::uniform3(-2i8..=2), 4..40)
        ) {
            let points: Vec<[f32; 3]> = points.iter().map(|p| p.map(f32::from)).collect();
            check_hull(&points)?;
        }
    }

    /// Closed, oriented, every point behind every face, genus 0, positive volume.
    fn check_hull(points: &[[f32; 3]]) -> Result<(), TestCaseError> {
        let Some(faces) = convex_hull(points) else {
            return Ok(());
        };
        assert_closed_and_oriented(&faces);
        let p: Vec<[f64; 3]> = points.iter().map(|&x| to_f64(x)).collect();
        let tolerance = 1e-5 * bounding_box_diagonal(points);
        for &t in &faces {
            for &x in &p {
                prop_assert!(signed_distance(&p, t, x) <= tolerance);
            }
        }
        // Euler: a closed surface of genus 0 over the corners used.
        let mut used: Vec<u32> = faces.iter().flatten().copied().collect();
        used.sort_unstable();
        used.dedup();
        prop_assert_eq!(
            used.len() as i64 - 3 * faces.len() as i64 / 2 + faces.len() as i64,
            2
        );
        prop_assert!(volume(points, &faces) > 0.0);
        Ok(())
    }
}
