//! Closes the cracks a face selection leaves with the candidates it rejected: the neural mesh
//! simplifier keeps candidate triangles above a probability threshold, and a gap one or two
//! triangles wide between kept faces is usually covered by a candidate just below it.
//!
//! Candidates, most probable first (ties by index), are added where at least two of their
//! edges lie on the border (one face each) and none already has two faces, oriented to run
//! those border edges against their faces; passes repeat while any is added, as each closed
//! crack can make the next one closable. The faces stay edge-manifold, and an added face runs
//! every border edge it closes against its neighbour; a candidate that would need two
//! orientations at once is skipped.

use std::collections::{HashMap, HashSet};

use crate::error::{Error, Result};

/// Per undirected edge: how many faces use it, and the direction of the last one added.
type EdgeUses = HashMap<(u32, u32), (u8, (u32, u32))>;

/// `faces` (edge-manifold, oriented) followed by the candidates added to close cracks (module
/// docs). Errors when the lengths of `candidates` and `probabilities` differ or a probability
/// is NaN.
///
/// ```
/// use meshgnn_geometry::close_cracks;
/// // Two faces of a fan around vertex 0 with the middle one missing, which the first
/// // candidate fills; the second touches the border on one edge only.
/// let kept = [[0, 1, 2], [0, 3, 4]];
/// let candidates = [[0, 2, 3], [1, 2, 5]];
/// let faces = close_cracks(&kept, &candidates, &[0.4, 0.3])?;
/// assert_eq!(faces, vec![[0, 1, 2], [0, 3, 4], [0, 2, 3]]);
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn close_cracks(
    faces: &[[u32; 3]],
    candidates: &[[u32; 3]],
    probabilities: &[f32],
) -> Result<Vec<[u32; 3]>> {
    if probabilities.len() != candidates.len() {
        return Err(Error::LengthMismatch {
            what: "candidate probabilities",
            expected: candidates.len(),
            actual: probabilities.len(),
        });
    }
    if probabilities.iter().any(|p| p.is_nan()) {
        return Err(Error::InvalidParameter {
            name: "candidate probabilities",
            message: "NaN probability".into(),
        });
    }
    let key = |a: u32, b: u32| (a.min(b), a.max(b));
    let sorted = |t: [u32; 3]| {
        let mut s = t;
        s.sort_unstable();
        s
    };
    let mut uses = EdgeUses::new();
    let add = |uses: &mut EdgeUses, [a, b, c]: [u32; 3]| {
        for (from, to) in [(a, b), (b, c), (c, a)] {
            let entry = uses.entry(key(from, to)).or_insert((0, (from, to)));
            *entry = (entry.0 + 1, (from, to));
        }
    };
    let mut present: HashSet<[u32; 3]> = HashSet::new();
    for &t in faces {
        add(&mut uses, t);
        present.insert(sorted(t));
    }
    let mut order: Vec<usize> = (0..candidates.len())
        .filter(|&f| {
            let [a, b, c] = candidates[f];
            a != b && b != c && a != c && !present.contains(&sorted(candidates[f]))
        })
        .collect();
    order.sort_by(|&a, &b| {
        probabilities[b]
            .total_cmp(&probabilities[a])
            .then(a.cmp(&b))
    });
    let mut out = faces.to_vec();
    let mut added = true;
    while added {
        added = false;
        order.retain(|&f| {
            let [a, b, c] = candidates[f];
            let edges = [(a, b), (b, c), (c, a)].map(|(u, v)| uses.get(&key(u, v)).copied());
            let border = edges.iter().filter(|e| matches!(e, Some((1, _)))).count();
            if border < 2 || edges.iter().any(|e| matches!(e, Some((2.., _)))) {
                return true;
            }
            // A border edge run u→v by its face asks for v→u here: `as_given` when the
            // candidate's own order runs it v→u.
            let wants: Vec<bool> = [(a, b), (b, c), (c, a)]
                .iter()
                .zip(&edges)
                .filter_map(|(&(u, _), e)| match e {
                    Some((1, (from, _))) => Some(*from != u),
                    _ => None,
                })
                .collect();
            if wants.iter().any(|&w| w != wants[0]) {
                return true;
            }
            let face = if wants[0] { [a, b, c] } else { [a, c, b] };
            add(&mut uses, face);
            out.push(face);
            added = true;
            false
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{TriMesh, boundary_loops, icosphere, is_edge_manifold, is_watertight};

    #[test]
    fn a_sphere_with_faces_missing_closes_from_its_own_faces_as_candidates() {
        let sphere = icosphere(2);
        let all = sphere.triangles().to_vec();
        // Every seventh face dropped: isolated one-face holes, each closable.
        let kept: Vec<[u32; 3]> = (0..all.len())
            .filter(|f| f % 7 != 0)
            .map(|f| all[f])
            .collect();
        // The candidates: every face, unoriented (corners rotated or swapped), plus a
        // wrong triangle across the sphere that must never fit.
        let mut candidates: Vec<[u32; 3]> = all.iter().map(|&[a, b, c]| [b, a, c]).collect();
        candidates.push([0, 40, 80]);
        let mut probabilities = vec![0.2; candidates.len()];
        *probabilities.last_mut().unwrap() = 0.9;
        let faces = close_cracks(&kept, &candidates, &probabilities).unwrap();
        let closed = TriMesh::new(sphere.vertices().to_vec(), faces.clone()).unwrap();
        assert_eq!(faces.len(), all.len());
        assert!(is_watertight(&closed) && is_edge_manifold(&closed));
        assert!(boundary_loops(&closed).is_empty());
        // Oriented like the sphere: every added face is one of its faces up to rotation.
        let rotations = |[a, b, c]: [u32; 3]| [[a, b, c], [b, c, a], [c, a, b]];
        for f in &faces[kept.len()..] {
            assert!(rotations(*f).iter().any(|r| all.contains(r)), "{f:?}");
        }
    }

    #[test]
    fn a_candidate_on_one_border_edge_or_on_a_full_edge_is_not_added() {
        // A strip of two faces; a candidate touching one border edge only stays out.
        let kept = [[0, 1, 2], [1, 3, 2]];
        assert_eq!(
            close_cracks(&kept, &[[2, 3, 4]], &[0.9]).unwrap(),
            kept.to_vec()
        );
        // (1, 2) already has two faces: no third.
        let fan = [[0, 1, 2], [1, 3, 2], [0, 4, 1]];
        let faces = close_cracks(&fan, &[[1, 2, 4]], &[0.9]).unwrap();
        assert_eq!(faces, fan.to_vec());
    }

    #[test]
    fn bad_lengths_and_nan_are_errors() {
        assert!(close_cracks(&[], &[[0, 1, 2]], &[]).is_err());
        assert!(close_cracks(&[], &[[0, 1, 2]], &[f32::NAN]).is_err());
    }
}
