//! Self-intersection count of a triangle mesh: triangle pairs that intersect, skipping pairs
//! that share a vertex. Used to check that generated shapes are valid (the thesis' ch. 6
//! triangle-collision loss targets the same defect).
//!
//! Narrow phase: T. Möller, "A fast triangle-triangle intersection test", Journal of Graphics
//! Tools 2(2), 1997 (interval overlap on the line of the two planes), in `f64`. Broad phase: a
//! uniform grid of cell size ≈ 2× the mean edge length; each triangle is binned by its
//! bounding box and each candidate pair is tested once (by the cell of the box's min corner).

use meshgnn_geometry::TriMesh;
use rayon::prelude::*;

use crate::vec3::{V3, cross, dot, sub, to_f64};

/// Signed distances of `t`'s corners to the plane of `(n, d)`, with tiny values snapped to 0.
fn plane_distances(n: V3, d: f64, t: &[V3; 3], eps: f64) -> [f64; 3] {
    t.map(|p| {
        let s = dot(n, p) + d;
        if s.abs() < eps { 0.0 } else { s }
    })
}

/// The interval of triangle `t` on the line direction `axis` (Möller's eq. 4-5).
fn interval(t: &[V3; 3], dist: [f64; 3], axis: V3) -> Option<(f64, f64)> {
    let proj = t.map(|p| dot(p, axis));
    // The vertex alone on its side of the plane.
    let lone = if dist[0] * dist[1] > 0.0 {
        2
    } else if dist[0] * dist[2] > 0.0 {
        1
    } else if dist[1] * dist[2] > 0.0 || dist[0] != 0.0 {
        0
    } else if dist[1] != 0.0 {
        1
    } else if dist[2] != 0.0 {
        2
    } else {
        return None; // coplanar
    };
    let (a, b) = ((lone + 1) % 3, (lone + 2) % 3);
    let at = |o: usize| {
        let denom = dist[lone] - dist[o];
        if denom == 0.0 {
            proj[o]
        } else {
            proj[lone] + (proj[o] - proj[lone]) * dist[lone] / denom
        }
    };
    let (x, y) = (at(a), at(b));
    Some((x.min(y), x.max(y)))
}

/// True when triangles `t` and `u` intersect (touching counts; coplanar pairs are tested by
/// edge crossings and containment in 2-D).
pub(crate) fn triangles_intersect(t: &[V3; 3], u: &[V3; 3]) -> bool {
    let scale = t
        .iter()
        .chain(u)
        .flat_map(|p| p.iter())
        .fold(0.0f64, |m, c| m.max(c.abs()))
        .max(1e-30);
    let eps = 1e-12 * scale;
    let n1 = cross(sub(t[1], t[0]), sub(t[2], t[0]));
    let d1 = -dot(n1, t[0]);
    let du = plane_distances(n1, d1, u, eps * crate::vec3::norm(n1));
    if du.iter().all(|&s| s > 0.0) || du.iter().all(|&s| s < 0.0) {
        return false;
    }
    let n2 = cross(sub(u[1], u[0]), sub(u[2], u[0]));
    let d2 = -dot(n2, u[0]);
    let dt = plane_distances(n2, d2, t, eps * crate::vec3::norm(n2));
    if dt.iter().all(|&s| s > 0.0) || dt.iter().all(|&s| s < 0.0) {
        return false;
    }
    let axis = cross(n1, n2);
    if dot(axis, axis) <= (eps * eps) * dot(n1, n1) * dot(n2, n2) || du.iter().all(|&s| s == 0.0) {
        return coplanar_intersect(n1, t, u);
    }
    match (interval(t, dt, axis), interval(u, du, axis)) {
        (Some((a0, a1)), Some((b0, b1))) => a0 <= b1 && b0 <= a1,
        _ => coplanar_intersect(n1, t, u),
    }
}

/// Coplanar triangles: project on the dominant plane and test edges and containment.
fn coplanar_intersect(n: V3, t: &[V3; 3], u: &[V3; 3]) -> bool {
    let k = (0..3)
        .max_by(|&i, &j| n[i].abs().total_cmp(&n[j].abs()))
        .unwrap_or(2);
    let (i, j) = ((k + 1) % 3, (k + 2) % 3);
    let p = t.map(|v| [v[i], v[j]]);
    let q = u.map(|v| [v[i], v[j]]);
    let orient = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    // `x` on segment `a`–`b`, given that the three are collinear.
    let on_segment = |a: [f64; 2], b: [f64; 2], x: [f64; 2]| {
        x[0] >= a[0].min(b[0])
            && x[0] <= a[0].max(b[0])
            && x[1] >= a[1].min(b[1])
            && x[1] <= a[1].max(b[1])
    };
    let seg = |a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]| {
        let (o1, o2) = (orient(a, b, c), orient(a, b, d));
        let (o3, o4) = (orient(c, d, a), orient(c, d, b));
        (o1 * o2 < 0.0 && o3 * o4 < 0.0)
            || (o1 == 0.0 && on_segment(a, b, c))
            || (o2 == 0.0 && on_segment(a, b, d))
            || (o3 == 0.0 && on_segment(c, d, a))
            || (o4 == 0.0 && on_segment(c, d, b))
    };
    let inside = |x: [f64; 2], tri: &[[f64; 2]; 3]| {
        let s = [
            orient(tri[0], tri[1], x),
            orient(tri[1], tri[2], x),
            orient(tri[2], tri[0], x),
        ];
        s.iter().all(|&v| v >= 0.0) || s.iter().all(|&v| v <= 0.0)
    };
    (0..3).any(|a| (0..3).any(|b| seg(p[a], p[(a + 1) % 3], q[b], q[(b + 1) % 3])))
        || inside(p[0], &q)
        || inside(q[0], &p)
}

/// Number of intersecting triangle pairs of `mesh` that share no vertex (0 for a valid
/// embedding). Grid broad phase, parallel over cells; O(F·k) for k triangles per cell.
///
/// ```
/// use meshgnn_data::self_intersections;
/// use meshgnn_geometry::{TriMesh, icosphere};
/// assert_eq!(self_intersections(&icosphere(2)), 0);
/// // Two triangles crossing each other.
/// let v = vec![[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0],
///              [0.5, 0.5, -1.0], [0.5, 0.5, 1.0], [3.0, 3.0, 0.0]];
/// let crossing = TriMesh::new(v, vec![[0, 1, 2], [3, 4, 5]])?;
/// assert_eq!(self_intersections(&crossing), 1);
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn self_intersections(mesh: &TriMesh) -> usize {
    self_intersecting_pairs(mesh).len()
}

/// The intersecting triangle pairs `[f, g]` (`f < g`, sorted) of `mesh` that share no vertex;
/// see [`self_intersections`].
///
/// ```
/// use meshgnn_data::self_intersecting_pairs;
/// use meshgnn_geometry::icosphere;
/// assert!(self_intersecting_pairs(&icosphere(1)).is_empty());
/// ```
pub fn self_intersecting_pairs(mesh: &TriMesh) -> Vec<[u32; 2]> {
    let tris: Vec<[V3; 3]> = (0..mesh.face_count())
        .map(|f| mesh.triangle_positions(f).map(to_f64))
        .collect();
    if tris.len() < 2 {
        return Vec::new();
    }
    let mut lo = [f64::MAX; 3];
    let mut hi = [f64::MIN; 3];
    let mut edge_sum = 0.0;
    for t in &tris {
        for p in t {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        edge_sum += crate::vec3::norm(sub(t[1], t[0]));
    }
    let cell = (2.0 * edge_sum / tris.len() as f64).max(1e-12);
    let dims = (0..3)
        .map(|k| (((hi[k] - lo[k]) / cell).floor() as usize + 1).min(1 << 20))
        .collect::<Vec<_>>();
    let cell_of = |p: V3| -> [usize; 3] {
        [0, 1, 2].map(|k| (((p[k] - lo[k]) / cell).floor().max(0.0) as usize).min(dims[k] - 1))
    };
    let key = |c: [usize; 3]| ((c[2] * dims[1] + c[1]) * dims[0] + c[0]) as u64;
    let boxes: Vec<([usize; 3], [usize; 3])> = tris
        .iter()
        .map(|t| {
            let mut a = [usize::MAX; 3];
            let mut b = [0; 3];
            for &p in t {
                let c = cell_of(p);
                for k in 0..3 {
                    a[k] = a[k].min(c[k]);
                    b[k] = b[k].max(c[k]);
                }
            }
            (a, b)
        })
        .collect();
    let mut entries: Vec<(u64, u32)> = Vec::new();
    for (f, (a, b)) in boxes.iter().enumerate() {
        for z in a[2]..=b[2] {
            for y in a[1]..=b[1] {
                for x in a[0]..=b[0] {
                    entries.push((key([x, y, z]), f as u32));
                }
            }
        }
    }
    entries.par_sort_unstable();
    let mut starts = vec![0usize];
    for i in 1..entries.len() {
        if entries[i].0 != entries[i - 1].0 {
            starts.push(i);
        }
    }
    starts.push(entries.len());
    let faces = mesh.triangles();
    let mut pairs: Vec<[u32; 2]> = starts
        .par_windows(2)
        .flat_map_iter(|w| {
            let group = &entries[w[0]..w[1]];
            let mut found = Vec::new();
            let Some(&(cell_key, _)) = group.first() else {
                return found;
            };
            for (i, &(_, f)) in group.iter().enumerate() {
                for &(_, g) in &group[i + 1..] {
                    let (fa, ga) = (faces[f as usize], faces[g as usize]);
                    if fa.iter().any(|v| ga.contains(v)) {
                        continue;
                    }
                    // Count the pair only in the first cell both boxes share.
                    let (ba, bb) = (boxes[f as usize], boxes[g as usize]);
                    let first = [0, 1, 2].map(|k| ba.0[k].max(bb.0[k]));
                    if key(first) != cell_key {
                        continue;
                    }
                    if triangles_intersect(&tris[f as usize], &tris[g as usize]) {
                        found.push([f.min(g), f.max(g)]);
                    }
                }
            }
            found
        })
        .collect();
    pairs.par_sort_unstable();
    pairs
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moller_known_cases() {
        let t = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        // Piercing.
        assert!(triangles_intersect(
            &t,
            &[[0.2, 0.2, -1.0], [0.2, 0.2, 1.0], [0.3, 0.9, 1.0]]
        ));
        // Parallel plane above.
        assert!(!triangles_intersect(
            &t,
            &[[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]]
        ));
        // Crossing the plane but outside the triangle.
        assert!(!triangles_intersect(
            &t,
            &[[2.0, 2.0, -1.0], [2.0, 2.0, 1.0], [3.0, 2.0, 0.0]]
        ));
        // Coplanar with collinear, disjoint edges (a regression: marching-tetrahedra planes).
        let far = [[1.5, 0.0, 0.0], [2.5, 0.0, 0.0], [1.5, 1.0, 0.0]];
        assert!(!triangles_intersect(&t, &far));
        // Coplanar overlapping and disjoint.
        assert!(triangles_intersect(
            &t,
            &[[0.2, 0.2, 0.0], [2.0, 0.2, 0.0], [0.2, 2.0, 0.0]]
        ));
        assert!(!triangles_intersect(
            &t,
            &[[2.0, 2.0, 0.0], [3.0, 2.0, 0.0], [2.0, 3.0, 0.0]]
        ));
    }

    #[test]
    fn grid_count_matches_brute_force_on_random_soup() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(1);
        let mut v = Vec::new();
        let mut f = Vec::new();
        for i in 0..150u32 {
            let c: [f32; 3] = [rng.random(), rng.random(), rng.random()];
            for _ in 0..3 {
                v.push([
                    c[0] + 0.2 * rng.random::<f32>(),
                    c[1] + 0.2 * rng.random::<f32>(),
                    c[2] + 0.2 * rng.random::<f32>(),
                ]);
            }
            f.push([3 * i, 3 * i + 1, 3 * i + 2]);
        }
        let mesh = TriMesh::new(v, f).unwrap();
        let tris: Vec<[V3; 3]> = (0..mesh.face_count())
            .map(|i| mesh.triangle_positions(i).map(to_f64))
            .collect();
        let mut brute = 0;
        for i in 0..tris.len() {
            for j in i + 1..tris.len() {
                if triangles_intersect(&tris[i], &tris[j]) {
                    brute += 1;
                }
            }
        }
        assert!(brute > 0);
        assert_eq!(self_intersections(&mesh), brute);
    }

    proptest::proptest! {
        #[test]
        fn intersection_is_symmetric_and_separated_triangles_never_meet(
            c in proptest::collection::vec(-1.0f64..1.0, 18),
            gap in 0.01f64..5.0,
        ) {
            let t = [[c[0], c[1], c[2]], [c[3], c[4], c[5]], [c[6], c[7], c[8]]];
            let u = [[c[9], c[10], c[11]], [c[12], c[13], c[14]], [c[15], c[16], c[17]]];
            proptest::prop_assert_eq!(triangles_intersect(&t, &u), triangles_intersect(&u, &t));
            // Shift u beyond t's x extent: disjoint bounding boxes cannot intersect.
            let shifted = u.map(|p| [p[0] + 2.0 + gap, p[1], p[2]]);
            proptest::prop_assert!(!triangles_intersect(&t, &shifted));
        }
    }
}
