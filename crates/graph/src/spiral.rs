//! Spiral sequences, the fixed neighbourhood ordering of spiral convolutions (thesis eq. 2.28,
//! `S(v, k) = {0-ring(v), 1-ring(v), …, k-ring(v)}` with each ring ordered; Lim et al. 2018,
//! "A simple approach to intrinsic correspondence learning on unstructured 3D meshes", ECCV-W;
//! Bouritsas et al. 2019, ICCV; Gong et al. 2019, "SpiralNet++", ICCV-W). Computed once per
//! template topology and shared by every mesh registered to it.
//!
//! # Ordering rule (topology only, so every registered mesh gets the same spirals)
//! - The *fan* of a vertex `u` is its neighbours in counter-clockwise order (the face
//!   orientation): `a` is followed by `b` when a face reads `(u, a, b)` cyclically. Interior
//!   vertices have a closed fan; boundary vertices an open fan from the neighbour across the
//!   boundary edge with no face before it, to the one across the other boundary edge.
//! - Ring 1 is the fan of `v`: for a boundary vertex from its open end; for an interior vertex
//!   starting at the *reference neighbour*, the vertex after `v` in `v`'s lowest-index face.
//! - Ring `r + 1` continues where ring `r` left off: for each vertex `x` of ring `r` in order,
//!   walk `x`'s fan counter-clockwise starting at the first vertex not yet in the spiral that
//!   follows one already in it (an open fan is treated as preceded by a taken vertex), and
//!   append every vertex not yet in the spiral. On a regular grid this yields concentric
//!   counter-clockwise rings (tested).
//! - The spiral is `v`, ring 1, ring 2, … until it reaches `length · dilation` entries (then
//!   truncated) or the component is exhausted (then padded by repeating the last entry; the
//!   number of real entries is kept in [`Spirals::valid`] so a model may mask or substitute
//!   a pad index `#V` instead). With `dilation = d`, entries `0, d, 2d, …` of the long spiral
//!   are kept (the dilated spiral of SpiralNet++).
//!
//! # Errors
//! The template must be edge-manifold, consistently oriented, and every vertex must lie on a
//! face with a single fan (no bow-tie vertices); the error names the edge or vertex. Faces
//! with a repeated vertex index are ignored.

use meshgnn_geometry::{TriMesh, edge_topology};
use rayon::prelude::*;

use crate::{Error, Result};

/// Spiral sequences of every vertex: `indices` is `#V×length` row-major `u32`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Spirals {
    /// Entries per spiral `L`.
    pub length: usize,
    /// `#V×L` vertex indices; row `v` starts with `v`.
    pub indices: Vec<u32>,
    /// `#V`: number of real (unpadded) entries of each row, `1..=L`.
    pub valid: Vec<u32>,
}

impl Spirals {
    /// The spiral of vertex `v` (empty when out of range).
    pub fn row(&self, v: usize) -> &[u32] {
        self.indices
            .get(v * self.length..(v + 1) * self.length)
            .unwrap_or(&[])
    }

    /// Number of spirals (vertices).
    pub fn len(&self) -> usize {
        self.valid.len()
    }

    /// True when there are no spirals.
    pub fn is_empty(&self) -> bool {
        self.valid.is_empty()
    }
}

/// A vertex fan: neighbours counter-clockwise, and whether it closes on itself.
#[derive(Debug, Clone, Default)]
struct Fan {
    neighbours: Vec<u32>,
    closed: bool,
}

/// The fan of `v` from the `(a, b)` pairs of its faces (in face order).
fn build_fan(v: u32, pairs: &[(u32, u32)]) -> Result<Fan> {
    let unusable = |message: String| Error::UnusableVertex { vertex: v, message };
    if pairs.is_empty() {
        return Err(unusable(
            "isolated: on no (non-degenerate) face; remove unreferenced vertices".into(),
        ));
    }
    for (i, p) in pairs.iter().enumerate() {
        if pairs[..i].iter().any(|q| q.0 == p.0 || q.1 == p.1) {
            return Err(unusable(format!(
                "faces around it are inconsistently oriented (edge to {} or {} used twice in one \
                 direction); orient the faces consistently",
                p.0, p.1
            )));
        }
    }
    let starts: Vec<u32> = pairs
        .iter()
        .map(|p| p.0)
        .filter(|a| !pairs.iter().any(|q| q.1 == *a))
        .collect();
    let (start, closed) = match starts.as_slice() {
        [] => (pairs[0].0, true),
        [s] => (*s, false),
        _ => {
            return Err(unusable(format!(
                "non-manifold: its faces form {} separate fans (a bow-tie); split the vertex",
                starts.len()
            )));
        }
    };
    let mut neighbours = Vec::with_capacity(pairs.len() + 1);
    let mut current = start;
    neighbours.push(current);
    while let Some(&(_, b)) = pairs.iter().find(|p| p.0 == current) {
        if closed && b == start {
            break;
        }
        neighbours.push(b);
        current = b;
        if neighbours.len() > pairs.len() + 1 {
            break;
        }
    }
    let expected = if closed { pairs.len() } else { pairs.len() + 1 };
    if neighbours.len() != expected {
        return Err(unusable(format!(
            "non-manifold: its {} faces form more than one fan; split the vertex",
            pairs.len()
        )));
    }
    Ok(Fan { neighbours, closed })
}

/// The fans of every vertex, in parallel.
fn vertex_fans(mesh: &TriMesh) -> Result<Vec<Fan>> {
    let n = mesh.vertex_count();
    // (vertex, a, b) for each corner of each non-degenerate face, grouped by vertex.
    let mut corners: Vec<(u32, u32, u32)> = mesh
        .triangles()
        .iter()
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .flat_map(|t| [(t[0], t[1], t[2]), (t[1], t[2], t[0]), (t[2], t[0], t[1])])
        .collect();
    // Stable: faces stay in index order within a vertex (the reference neighbour rule).
    corners.sort_by_key(|c| c.0);
    let mut offsets = vec![0usize; n + 1];
    for c in &corners {
        offsets[c.0 as usize + 1] += 1;
    }
    for v in 0..n {
        offsets[v + 1] += offsets[v];
    }
    let pairs: Vec<(u32, u32)> = corners.iter().map(|c| (c.1, c.2)).collect();
    (0..n)
        .into_par_iter()
        .map(|v| build_fan(v as u32, &pairs[offsets[v]..offsets[v + 1]]))
        .collect()
}

/// Appends to `next` the vertices of the ring after `ring`, by the module's rule.
fn next_ring(fans: &[Fan], ring: &[u32], taken: &mut Vec<u32>, next: &mut Vec<u32>) {
    next.clear();
    for &x in ring {
        let fan = &fans[x as usize];
        let m = fan.neighbours.len();
        let is_taken = |taken: &Vec<u32>, w: u32| taken.contains(&w);
        // First position whose vertex is new and whose predecessor is taken.
        let start = (0..m).find(|&j| {
            let prev_taken = if j == 0 {
                !fan.closed || is_taken(taken, fan.neighbours[m - 1])
            } else {
                is_taken(taken, fan.neighbours[j - 1])
            };
            prev_taken && !is_taken(taken, fan.neighbours[j])
        });
        let Some(start) = start else { continue };
        for j in 0..m {
            let w = fan.neighbours[(start + j) % m];
            if !is_taken(taken, w) {
                taken.push(w);
                next.push(w);
            }
        }
    }
}

/// Spiral sequence of every vertex of the template `mesh` (eq. 2.28; rule in the module
/// docs): `#V×length` indices, starting at the vertex itself, with `dilation ≥ 1` keeping
/// every `dilation`-th entry. Parallel over vertices; deterministic.
///
/// Errors when `length` or `dilation` is 0, an edge has more than two faces, or a vertex is
/// isolated, a bow-tie or surrounded by inconsistently oriented faces.
///
/// ```
/// use meshgnn_graph::spiral_sequences;
/// // Vertex 6 of the 4×4 grid is (1, 1): its ring 1 runs counter-clockwise from (0, 0).
/// let spirals = spiral_sequences(&meshgnn_geometry::grid_plane(4, 4), 7, 1)?;
/// assert_eq!(spirals.row(6), &[6, 0, 1, 7, 12, 11, 5]);
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn spiral_sequences(mesh: &TriMesh, length: usize, dilation: usize) -> Result<Spirals> {
    if length == 0 {
        return Err(Error::InvalidParameter {
            name: "length",
            message: "a spiral holds at least the vertex itself (length >= 1)".into(),
        });
    }
    if dilation == 0 {
        return Err(Error::InvalidParameter {
            name: "dilation",
            message: "must be at least 1 (1 = no dilation)".into(),
        });
    }
    let topology = edge_topology(mesh);
    if let Some((e, faces)) = topology.valences().enumerate().find(|&(_, f)| f > 2) {
        let [a, b] = topology.edges().get(e).copied().unwrap_or_default();
        return Err(Error::NonManifoldEdge { a, b, faces });
    }
    let fans = vertex_fans(mesh)?;
    let long = length.saturating_mul(dilation);
    let rows: Vec<(Vec<u32>, u32)> = (0..mesh.vertex_count() as u32)
        .into_par_iter()
        .map_init(
            || (Vec::new(), Vec::new()),
            |(ring, next), v| {
                let mut spiral = vec![v];
                ring.clear();
                let fan = &fans[v as usize];
                for &w in &fan.neighbours {
                    spiral.push(w);
                    ring.push(w);
                }
                while spiral.len() < long && !ring.is_empty() {
                    next_ring(&fans, ring, &mut spiral, next);
                    std::mem::swap(ring, next);
                }
                spiral.truncate(long);
                let real = spiral.len();
                let last = spiral.last().copied().unwrap_or(v);
                spiral.resize(long, last);
                let kept: Vec<u32> = spiral.into_iter().step_by(dilation).collect();
                let valid = real.div_ceil(dilation) as u32;
                (kept, valid)
            },
        )
        .collect();
    let mut indices = Vec::with_capacity(rows.len() * length);
    let mut valid = Vec::with_capacity(rows.len());
    for (row, count) in rows {
        indices.extend_from_slice(&row);
        valid.push(count);
    }
    Ok(Spirals {
        length,
        indices,
        valid,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshgnn_geometry::{grid_plane, icosphere, subdivided_cube};

    #[test]
    fn grid_interior_and_boundary_spirals_match_hand_built_sequences() {
        // Derived by hand from grid_plane's faces (cells split (i, j)-(i+1, j+1)), see the
        // module rule: concentric counter-clockwise rings.
        let mesh = grid_plane(4, 4);
        let s = spiral_sequences(&mesh, 14, 1).unwrap();
        assert_eq!(s.row(6), &[6, 0, 1, 7, 12, 11, 5, 2, 8, 13, 18, 17, 16, 10]);
        let s = spiral_sequences(&mesh, 12, 1).unwrap();
        assert_eq!(s.row(2), &[2, 3, 8, 7, 1, 4, 9, 14, 13, 12, 6, 0]);
        assert_eq!(s.valid[2], 12);
    }

    #[test]
    fn truncation_dilation_and_padding() {
        let mesh = grid_plane(4, 4);
        let s = spiral_sequences(&mesh, 5, 2).unwrap();
        // Long spiral of vertex 2: 2 3 8 7 1 4 9 14 13 12 → every second entry.
        assert_eq!(s.row(2), &[2, 8, 1, 9, 13]);
        let tiny = grid_plane(1, 1);
        let s = spiral_sequences(&tiny, 6, 1).unwrap();
        // Vertices (0,0)=0 (1,0)=1 (0,1)=2 (1,1)=3, faces [0,1,3] [0,3,2]: open fan of 0 is
        // 1 → 3 → 2; then padding repeats the last entry.
        assert_eq!(s.row(0), &[0, 1, 3, 2, 2, 2]);
        assert_eq!(s.valid[0], 4);
    }

    #[test]
    fn closed_meshes_enumerate_each_vertex_once_per_spiral_deterministically() {
        for mesh in [icosphere(2), subdivided_cube(4)] {
            let n = mesh.vertex_count();
            let a = spiral_sequences(&mesh, 30, 1).unwrap();
            let b = spiral_sequences(&mesh, 30, 1).unwrap();
            assert_eq!(a, b);
            let adjacency = crate::vertex_adjacency(&mesh).unwrap();
            for v in 0..n {
                let row = a.row(v);
                assert_eq!(row[0] as usize, v);
                let mut sorted = row.to_vec();
                sorted.sort_unstable();
                sorted.dedup();
                assert_eq!(sorted.len(), 30, "vertex {v} repeats an entry");
                // Ring 1 is exactly the 1-ring, each consecutive pair adjacent (a fan).
                let valence = adjacency.row(v).0.len();
                let mut ring1 = row[1..=valence].to_vec();
                for w in ring1.windows(2) {
                    assert!(adjacency.get(w[0] as usize, w[1] as usize) == 1.0);
                }
                ring1.sort_unstable();
                assert_eq!(ring1, adjacency.row(v).0);
                // As sets, the spiral is the k-disk of eq. 2.27, ring after ring.
                let mut at = 0;
                for ring in crate::k_rings(&adjacency, v as u32, 3).unwrap() {
                    let end = (at + ring.len()).min(30);
                    let mut got = row[at..end].to_vec();
                    got.sort_unstable();
                    if end - at == ring.len() {
                        assert_eq!(got, ring, "vertex {v}");
                    } else {
                        assert!(got.iter().all(|w| ring.contains(w)));
                    }
                    at = end;
                }
            }
        }
    }

    #[test]
    fn unusable_templates_are_reported() {
        // Three faces on edge (0, 1).
        let v = vec![
            [0.0; 3],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        let mesh = TriMesh::new(v.clone(), vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]]).unwrap();
        assert!(matches!(
            spiral_sequences(&mesh, 4, 1),
            Err(Error::NonManifoldEdge {
                a: 0,
                b: 1,
                faces: 3
            })
        ));
        // Vertex 4 unreferenced.
        let mesh = TriMesh::new(v.clone(), vec![[0, 1, 2], [1, 0, 3]]).unwrap();
        assert!(matches!(
            spiral_sequences(&mesh, 4, 1),
            Err(Error::UnusableVertex { vertex: 4, .. })
        ));
        // Bow-tie at vertex 0: two triangles sharing only that vertex.
        let w = vec![
            [0.0; 3],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [-1.0, 0.0, 0.0],
            [-1.0, -1.0, 0.0],
        ];
        let mesh = TriMesh::new(w, vec![[0, 1, 2], [0, 3, 4]]).unwrap();
        assert!(matches!(
            spiral_sequences(&mesh, 4, 1),
            Err(Error::UnusableVertex { vertex: 0, .. })
        ));
        assert!(spiral_sequences(&grid_plane(1, 1), 0, 1).is_err());
        assert!(spiral_sequences(&grid_plane(1, 1), 3, 0).is_err());
    }
}
