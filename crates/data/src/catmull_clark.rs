//! Catmull–Clark subdivision of a quad mesh, as a linear stencil.
//!
//! The hand template is a coarse quad cage refined by Catmull–Clark (E. Catmull and J. Clark,
//! "Recursively generated B-spline surfaces on arbitrary topological meshes", CAD 1978), with
//! the boundary rules of Biermann, Levin and Zorin (SIGGRAPH 2000, crease/boundary curves as
//! cubic B-splines). Because one refinement is linear in the coarse positions, it is stored
//! once as a sparse stencil (each fine vertex a weighted sum of coarse vertices) and applied to
//! every generated cage: the topology is fixed by construction and applying it is O(nnz).
//!
//! # Conventions
//! - Quads are counter-clockwise seen from outside; children keep the orientation.
//! - Fine vertex order: the `#V` vertex points, then one point per edge (edges sorted by
//!   `(min, max)` vertex index), then one point per face.

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::vec3::V3;

/// One level of Catmull–Clark refinement: the refined quads and the stencil that maps coarse
/// positions `#V×3` to refined positions `#V'×3`.
#[derive(Debug, Clone, PartialEq)]
pub struct QuadSubdivision {
    quads: Vec<[u32; 4]>,
    offsets: Vec<usize>,
    entries: Vec<(u32, f64)>,
    coarse_count: usize,
}

impl QuadSubdivision {
    /// The refined quads `4·#F×4`.
    pub fn quads(&self) -> &[[u32; 4]] {
        &self.quads
    }

    /// Number of refined vertices `#V'`.
    pub fn vertex_count(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Number of coarse vertices `#V` the stencil expects.
    pub fn coarse_count(&self) -> usize {
        self.coarse_count
    }

    /// The stencil row of refined vertex `v`: `(coarse vertex, weight)` pairs summing to 1.
    pub fn stencil(&self, v: usize) -> &[(u32, f64)] {
        match (self.offsets.get(v), self.offsets.get(v + 1)) {
            (Some(&a), Some(&b)) => self.entries.get(a..b).unwrap_or(&[]),
            _ => &[],
        }
    }

    /// Refines `coarse: #V×3` to `#V'×3` (rayon-parallel over rows; deterministic).
    ///
    /// ```
    /// use meshgnn_data::catmull_clark;
    /// // One quad: the face point of the refined mesh is the centroid.
    /// let level = catmull_clark(&[[0, 1, 2, 3]], 4)?;
    /// let fine = level.apply(&[[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [2.0, 2.0, 0.0], [0.0, 2.0, 0.0]])?;
    /// assert_eq!(fine.len(), 9);
    /// assert_eq!(fine[8], [1.0, 1.0, 0.0]);
    /// # Ok::<(), meshgnn_data::Error>(())
    /// ```
    pub fn apply(&self, coarse: &[V3]) -> Result<Vec<V3>> {
        if coarse.len() != self.coarse_count {
            return Err(Error::Topology {
                element: "subdivision input".into(),
                message: format!(
                    "expected {} coarse vertices, got {}",
                    self.coarse_count,
                    coarse.len()
                ),
            });
        }
        Ok((0..self.vertex_count())
            .into_par_iter()
            .map(|v| {
                let mut p = [0.0; 3];
                for &(c, w) in self.stencil(v) {
                    if let Some(q) = coarse.get(c as usize) {
                        p[0] += w * q[0];
                        p[1] += w * q[1];
                        p[2] += w * q[2];
                    }
                }
                p
            })
            .collect())
    }
}

/// One Catmull–Clark refinement of `quads: #F×4` over `vertex_count` vertices.
///
/// Fails on an index out of range, a repeated index in a quad, an edge shared by more than
/// two quads or a boundary vertex with other than two boundary edges (non-manifold input).
///
/// ```
/// use meshgnn_data::catmull_clark;
/// let level = catmull_clark(&[[0, 1, 2, 3]], 4)?;
/// // 4 vertex points + 4 edge points + 1 face point, 4 child quads.
/// assert_eq!((level.vertex_count(), level.quads().len()), (9, 4));
/// # Ok::<(), meshgnn_data::Error>(())
/// ```
pub fn catmull_clark(quads: &[[u32; 4]], vertex_count: usize) -> Result<QuadSubdivision> {
    for (f, q) in quads.iter().enumerate() {
        for (i, &v) in q.iter().enumerate() {
            if v as usize >= vertex_count {
                return Err(Error::Topology {
                    element: format!("quad {f}"),
                    message: format!("vertex {v} out of range (#V = {vertex_count})"),
                });
            }
            if q[(i + 1) % 4] == v {
                return Err(Error::Topology {
                    element: format!("quad {f}"),
                    message: format!("repeats vertex {v}"),
                });
            }
        }
    }
    // Undirected edges with their incident quads.
    let mut half: Vec<(u32, u32, u32, u8)> = Vec::with_capacity(quads.len() * 4);
    for (f, q) in quads.iter().enumerate() {
        for i in 0..4 {
            let (a, b) = (q[i], q[(i + 1) % 4]);
            half.push((a.min(b), a.max(b), f as u32, i as u8));
        }
    }
    half.sort_unstable();
    let mut edges: Vec<[u32; 2]> = Vec::new();
    let mut edge_faces: Vec<Vec<u32>> = Vec::new();
    let mut quad_edges = vec![[0u32; 4]; quads.len()];
    for &(a, b, f, i) in &half {
        if edges.last() != Some(&[a, b]) {
            edges.push([a, b]);
            edge_faces.push(Vec::with_capacity(2));
        }
        let e = edges.len() - 1;
        if let Some(faces) = edge_faces.last_mut() {
            faces.push(f);
            if faces.len() > 2 {
                return Err(Error::Topology {
                    element: format!("edge ({a}, {b})"),
                    message: "shared by more than two quads".into(),
                });
            }
        }
        if let Some(slot) = quad_edges.get_mut(f as usize) {
            slot[i as usize] = e as u32;
        }
    }
    let (nv, ne) = (vertex_count, edges.len());
    let corner = |f: u32| quads.get(f as usize).copied().unwrap_or_default();

    // Per vertex: incident edges and faces.
    let mut vertex_edges: Vec<Vec<u32>> = vec![Vec::new(); nv];
    for (e, &[a, b]) in edges.iter().enumerate() {
        vertex_edges[a as usize].push(e as u32);
        vertex_edges[b as usize].push(e as u32);
    }
    let mut vertex_faces: Vec<Vec<u32>> = vec![Vec::new(); nv];
    for (f, q) in quads.iter().enumerate() {
        for &v in q {
            vertex_faces[v as usize].push(f as u32);
        }
    }

    let mut rows: Vec<Vec<(u32, f64)>> = Vec::with_capacity(nv + ne + quads.len());
    // Vertex points.
    for v in 0..nv {
        let mut row = Vec::new();
        let inc = &vertex_edges[v];
        let boundary: Vec<u32> = inc
            .iter()
            .copied()
            .filter(|&e| edge_faces[e as usize].len() == 1)
            .collect();
        let other = |e: u32| {
            let [a, b] = edges[e as usize];
            if a as usize == v { b } else { a }
        };
        if inc.is_empty() {
            row.push((v as u32, 1.0));
        } else if !boundary.is_empty() {
            if boundary.len() != 2 {
                return Err(Error::Topology {
                    element: format!("vertex {v}"),
                    message: format!("has {} boundary edges (expected 2)", boundary.len()),
                });
            }
            row.push((v as u32, 0.75));
            row.push((other(boundary[0]), 0.125));
            row.push((other(boundary[1]), 0.125));
        } else {
            let n = inc.len() as f64;
            let faces = &vertex_faces[v];
            let nf = faces.len() as f64;
            for &f in faces {
                for c in corner(f) {
                    row.push((c, 1.0 / (nf * n * 4.0)));
                }
            }
            for &e in inc {
                row.push((v as u32, 1.0 / (n * n)));
                row.push((other(e), 1.0 / (n * n)));
            }
            row.push((v as u32, (n - 3.0) / n));
        }
        rows.push(row);
    }
    // Edge points.
    for (e, &[a, b]) in edges.iter().enumerate() {
        let faces = &edge_faces[e];
        let mut row = Vec::new();
        if faces.len() == 1 {
            row.push((a, 0.5));
            row.push((b, 0.5));
        } else {
            row.push((a, 0.25));
            row.push((b, 0.25));
            for &f in faces {
                for c in corner(f) {
                    row.push((c, 1.0 / 16.0));
                }
            }
        }
        rows.push(row);
    }
    // Face points.
    for q in quads {
        rows.push(q.iter().map(|&c| (c, 0.25)).collect());
    }

    let mut offsets = Vec::with_capacity(rows.len() + 1);
    let mut entries: Vec<(u32, f64)> = Vec::new();
    offsets.push(0);
    for mut row in rows {
        row.sort_unstable_by_key(|x| x.0);
        let start = entries.len();
        for (c, w) in row {
            let merge = entries.len() > start && entries.last().map(|e| e.0) == Some(c);
            match entries.last_mut() {
                Some(last) if merge => last.1 += w,
                _ => entries.push((c, w)),
            }
        }
        offsets.push(entries.len());
    }

    let mut fine = Vec::with_capacity(quads.len() * 4);
    for (f, q) in quads.iter().enumerate() {
        let fp = (nv + ne + f) as u32;
        let qe = quad_edges[f];
        for i in 0..4 {
            let ep_next = (nv as u32) + qe[i];
            let ep_prev = (nv as u32) + qe[(i + 3) % 4];
            fine.push([q[i], ep_next, fp, ep_prev]);
        }
    }
    Ok(QuadSubdivision {
        quads: fine,
        offsets,
        entries,
        coarse_count: nv,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed cube cage: 8 vertices, 6 outward quads.
    fn cube() -> (Vec<V3>, Vec<[u32; 4]>) {
        let v = (0..8)
            .map(|i| {
                [
                    if i & 1 == 1 { 1.0 } else { -1.0 },
                    if i & 2 == 2 { 1.0 } else { -1.0 },
                    if i & 4 == 4 { 1.0 } else { -1.0 },
                ]
            })
            .collect();
        let q = vec![
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        (v, q)
    }

    #[test]
    fn stencil_rows_sum_to_one() {
        let (_, q) = cube();
        let level = catmull_clark(&q, 8).unwrap();
        for v in 0..level.vertex_count() {
            let s: f64 = level.stencil(v).iter().map(|e| e.1).sum();
            assert!((s - 1.0).abs() < 1e-12, "row {v} sums to {s}");
        }
        assert_eq!(level.vertex_count(), 8 + 12 + 6);
    }

    #[test]
    fn cube_corner_matches_hand_computed_rule() {
        // Valence 3 corner (1,1,1): F = avg face points = (2/3)(1,1,1)... computed by hand:
        // face points (1,0,0),(0,1,0),(0,0,1) → F = (1/3,1/3,1/3); edge midpoints
        // (1,1,0),(1,0,1),(0,1,1) → R = (2/3,2/3,2/3); v' = (F + 2R + 0·P)/3 = (5/9,5/9,5/9).
        let (v, q) = cube();
        let fine = catmull_clark(&q, 8).unwrap().apply(&v).unwrap();
        for c in fine[7] {
            assert!((c - 5.0 / 9.0).abs() < 1e-12);
        }
    }

    #[test]
    fn planar_grid_interior_stays_on_plane_and_boundary_rule_holds() {
        // 2×1 quads in the z = 0 plane; the shared middle edge is interior.
        let v = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
            [2.0, 1.0, 0.0],
        ];
        let q = vec![[0, 1, 4, 3], [1, 2, 5, 4]];
        let fine = catmull_clark(&q, 6).unwrap().apply(&v).unwrap();
        // Boundary vertex 1 = (3/4)(1,0) + (1/8)((0,0) + (2,0)).
        assert_eq!(fine[1], [1.0, 0.0, 0.0]);
        assert!(fine.iter().all(|p| p[2] == 0.0));
    }

    #[test]
    fn rejects_non_manifold_edges() {
        let q = vec![[0, 1, 2, 3], [1, 0, 4, 5], [0, 1, 6, 7]];
        assert!(catmull_clark(&q, 8).is_err());
        assert!(catmull_clark(&[[0, 1, 2, 9]], 4).is_err());
    }
}
