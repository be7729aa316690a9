//! Self-intersection count of a triangle mesh: triangle pairs that intersect, skipping pairs
//! that share a vertex. Used to check that generated shapes are valid (the thesis' ch. 6
//! triangle-collision loss targets the same defect).
//!
//! Narrow phase: [`meshgnn_losses::predicates::triangles_meet`] (Möller 1997). Broad phase: a
//! uniform grid of cell size ≈ 2× the mean edge length; each triangle is binned by its
//! bounding box and each candidate pair is tested once (by the cell of the box's min corner).

use meshgnn_geometry::TriMesh;
use meshgnn_losses::predicates::triangles_meet;
use rayon::prelude::*;

use crate::vec3::{V3, sub, to_f64};

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
                    if triangles_meet(&tris[f as usize], &tris[g as usize]) {
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
                if triangles_meet(&tris[i], &tris[j]) {
                    brute += 1;
                }
            }
        }
        assert!(brute > 0);
        assert_eq!(self_intersections(&mesh), brute);
    }
}
