//! Geometric features of each candidate triangle, read by the face classifier beside the eq.
//! 6.5 prior. Beyond the thesis, whose classifier sees only the prior and the eq. 6.6 relative
//! positions: trained on the Voronoi-dual targets ([`super::DualTargets`]) that classifier
//! stayed near chance (balanced cross-entropy 0.57 after 75 steps, measured), since nothing it
//! reads says whether a triangle lies on the surface or whether other sampled vertices crowd
//! it. Each feature is what a restricted Delaunay triangulation decides by:
//!
//! 0. **normal agreement** `|n_t · n̄|`: the triangle's unit normal against the mean of the
//!    input's vertex normals at its corners (1 on the surface, near 0 across it);
//! 1. **longest edge / spacing** and 2. **shortest edge / spacing**, with the spacing the mean
//!    over the corners of the distance to their nearest other sampled vertex;
//! 3. **smallest angle** over 60°;
//! 4. **emptiness** of the triangle's circumsphere (centre in its plane): the smallest
//!    `(|q − c|² − R²) / R²` over the `EMPTINESS_NEIGHBOURS` sampled vertices nearest the
//!    centre other than the corners, clamped to `[−1, 1]` (negative: some vertex intrudes, as
//!    in no Delaunay triangle);
//! 5. **dual membership**: 1 when the triangle is one of the nearest-seed dual of the sampled
//!    vertices over the input ([`meshgnn_geometry::nearest_seed_dual_triangles`]), else 0.
//!    Features 0-4 see the sampled vertices only, so where four of them are nearly
//!    cocircular both diagonals look alike and a classifier keeps both (raw WA 70 %,
//!    docs/mesh_simplifier_model.md); the input surface between them decides.
//!
//! Computed once on the host per pass, in the unit-sphere frame, one triangle per parallel
//! task.

use std::collections::HashSet;

use meshgnn_geometry::SpatialIndex;
use meshgnn_geometry::vec3::{cross, dot, norm, sub, to_f64};
use rayon::prelude::*;

use crate::Result;

/// Features per candidate.
pub const CANDIDATE_FEATURES: usize = 6;

/// Sampled vertices nearest a circumcentre checked for intrusion.
const EMPTINESS_NEIGHBOURS: usize = 8;

/// The features of `triangles` over the sampled `corners` (with the input's unit vertex
/// `normals` at them and their nearest-seed `dual`, in the same numbering),
/// `#F×CANDIDATE_FEATURES`, row-major.
pub fn candidate_features(
    corners: &[[f32; 3]],
    normals: &[[f32; 3]],
    triangles: &[[u32; 3]],
    dual: &[[u32; 3]],
) -> Result<Vec<f32>> {
    let index = SpatialIndex::new(corners)?;
    let dual: HashSet<[u32; 3]> = dual.iter().map(sorted_corners).collect();
    let spacing: Vec<f64> = (0..corners.len())
        .into_par_iter()
        .map_init(Vec::new, |out, i| {
            index.nearest(&corners[i], 1, Some(i as u32), out);
            out.first().map_or(1.0, |&(d2, _)| f64::from(d2).sqrt())
        })
        .collect();
    let rows: Vec<[f32; CANDIDATE_FEATURES]> = triangles
        .par_iter()
        .map_init(Vec::new, |out, t| {
            let [a, b, c] = t.map(|v| to_f64(corners[v as usize]));
            let edges = [sub(b, a), sub(c, b), sub(a, c)];
            let lengths = edges.map(norm);
            let normal = cross(edges[0], sub(c, a));
            let area2 = norm(normal);
            let mean_normal = t
                .iter()
                .map(|&v| to_f64(normals[v as usize]))
                .fold([0.0; 3], |s, n| [s[0] + n[0], s[1] + n[1], s[2] + n[2]]);
            let agreement = match (area2, norm(mean_normal)) {
                (x, y) if x > 0.0 && y > 0.0 => dot(normal, mean_normal).abs() / (x * y),
                _ => 0.0,
            };
            let h = t.iter().map(|&v| spacing[v as usize]).sum::<f64>() / 3.0;
            let h = if h > 0.0 { h } else { 1.0 };
            let longest = lengths.iter().copied().fold(0.0, f64::max);
            let shortest = lengths.iter().copied().fold(f64::INFINITY, f64::min);
            let smallest_angle = (0..3)
                .map(|k| {
                    let (u, v) = (edges[k], edges[(k + 2) % 3]);
                    let cos =
                        -dot(u, v) / (lengths[k] * lengths[(k + 2) % 3]).max(f64::MIN_POSITIVE);
                    cos.clamp(-1.0, 1.0).acos()
                })
                .fold(f64::INFINITY, f64::min);
            let emptiness = circumsphere_emptiness(&index, [a, b, c], t, out);
            [
                agreement,
                (longest / h).min(10.0),
                (shortest / h).min(10.0),
                smallest_angle / std::f64::consts::FRAC_PI_3,
                emptiness,
                f64::from(u8::from(dual.contains(&sorted_corners(t)))),
            ]
            .map(|f| f as f32)
        })
        .collect();
    Ok(rows.into_flattened())
}

/// The corners in increasing order: one key for a triangle however it is oriented.
pub(crate) fn sorted_corners(t: &[u32; 3]) -> [u32; 3] {
    let mut key = *t;
    key.sort_unstable();
    key
}

/// Feature 4 of the module docs; −1 (crowded) for a degenerate triangle, which has no circle.
fn circumsphere_emptiness(
    index: &SpatialIndex,
    [a, b, c]: [[f64; 3]; 3],
    corners: &[u32; 3],
    out: &mut Vec<(f32, u32)>,
) -> f64 {
    let (ab, ac) = (sub(b, a), sub(c, a));
    let n = cross(ab, ac);
    let n2 = dot(n, n);
    if n2 <= 0.0 {
        return -1.0;
    }
    // Circumcentre a + ((|ac|² (n × ab)) + (|ab|² (ac × n))) / (2|n|²).
    let (p, q) = (cross(n, ab), cross(ac, n));
    let (s, t) = (dot(ac, ac), dot(ab, ab));
    let centre = [0, 1, 2].map(|k| a[k] + (s * p[k] + t * q[k]) / (2.0 * n2));
    let r2 = dot(sub(a, centre), sub(a, centre));
    let query = centre.map(|x| x as f32);
    index.nearest(&query, EMPTINESS_NEIGHBOURS + 3, None, out);
    out.iter()
        .filter(|(_, id)| !corners.contains(id))
        .map(|&(d2, _)| (f64::from(d2) - r2) / r2)
        .fold(1.0, f64::min)
        .clamp(-1.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn features_of_a_hand_computed_square() {
        // A unit square split along (0, 2); normals +z. Triangle [0, 1, 2] is right-angled and
        // its circumcircle (centre (0.5, 0.5), R² = 0.5) passes through vertex 3 (emptiness 0);
        // a sliver [0, 1, 4] with 4 far above the plane disagrees with the normals.
        let v = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.5, 0.0, 3.0],
        ];
        let n = [[0.0, 0.0, 1.0]; 5];
        // The dual holds the first triangle, the other way round.
        let f = candidate_features(&v, &n, &[[0, 1, 2], [0, 1, 4]], &[[2, 1, 0]]).unwrap();
        let first = &f[..CANDIDATE_FEATURES];
        let want = [1.0, 2f32.sqrt(), 1.0, 0.75, 0.0, 1.0];
        for (got, want) in first.iter().zip(want) {
            assert!((got - want).abs() < 1e-5, "{first:?}");
        }
        let second = &f[CANDIDATE_FEATURES..];
        assert!(second[0] < 1e-6, "vertical triangle: {second:?}");
        // Circle through 0, 1, 4: centre (0.5, 0, 35/24), R² = 0.25 + (35/24)²; vertices 2
        // and 3 lie 1 off its plane, at |q − c|² = R² + 1.
        let r2 = 0.25 + (35.0f32 / 24.0).powi(2);
        assert!((second[4] - 1.0 / r2).abs() < 1e-5, "{second:?}");
        assert_eq!(second[5], 0.0, "not in the dual");
        // A vertex inside the first circle: |q − c|² = 0.01 against R² = 0.5.
        let mut crowded = v.to_vec();
        crowded.push([0.6, 0.5, 0.0]);
        let f = candidate_features(&crowded, &[[0.0, 0.0, 1.0]; 6], &[[0, 1, 2]], &[]).unwrap();
        assert!((f[4] + 0.98).abs() < 1e-5, "{f:?}");
    }
}
