//! Surface extraction from a signed distance function by marching tetrahedra on a cubic grid
//! split into six Kuhn tetrahedra per cube (A. Doi and A. Koide, "An efficient method of
//! triangulating equi-valued surfaces by using tetrahedral cells", IEICE 1991).
//!
//! Chosen over marching cubes and surface nets because the zero set of a piecewise-linear
//! function on a simplicial complex is always a closed 2-manifold (no ambiguous cases): every
//! generated shape is watertight and edge- and vertex-manifold by construction, which the
//! simplification benchmarks need. Vertices are shared through a global sort of edge keys, so
//! the result is identical for any thread count.
//!
//! # Conventions
//! - `sdf < 0` inside. Values exactly 0 count as outside. Triangles face outwards.

use meshgnn_geometry::TriMesh;
use rayon::prelude::*;

use crate::error::{Result, invalid};
use crate::vec3::{V3, cross, dot, sub, to_f32};

/// The six Kuhn tetrahedra of a cube, as corner bit masks (x = 1, y = 2, z = 4).
const KUHN: [[u8; 4]; 6] = [
    [0, 1, 3, 7],
    [0, 1, 5, 7],
    [0, 2, 3, 7],
    [0, 2, 6, 7],
    [0, 4, 5, 7],
    [0, 4, 6, 7],
];

/// Meshes the zero set of `sdf` inside the box `[lo, hi]` on a grid with `resolution` cells
/// along the longest side (`8..=1024`). The mesh is always closed: grid nodes on the box
/// boundary count as outside, so a shape reaching the box is capped by its faces.
///
/// ```
/// use meshgnn_data::marching_tetrahedra;
/// use meshgnn_geometry::mesh_report;
/// let sphere = |p: [f64; 3]| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt() - 1.0;
/// let mesh = marching_tetrahedra(&sphere, [-1.2; 3], [1.2; 3], 24)?;
/// let report = mesh_report(&mesh);
/// assert!(report.watertight && report.edge_manifold && report.vertex_manifold);
/// let r = mesh.vertices().iter().map(|p| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt());
/// assert!(r.clone().all(|r| (r - 1.0).abs() < 0.02));
/// # Ok::<(), meshgnn_data::Error>(())
/// ```
pub fn marching_tetrahedra(
    sdf: &(dyn Fn(V3) -> f64 + Sync),
    lo: V3,
    hi: V3,
    resolution: usize,
) -> Result<TriMesh> {
    if !(8..=1024).contains(&resolution) {
        return Err(invalid("resolution", resolution, "must be in 8..=1024"));
    }
    let extent = (0..3).map(|k| hi[k] - lo[k]).fold(0.0f64, f64::max);
    if !(extent > 0.0 && extent.is_finite()) || (0..3).any(|k| hi[k] < lo[k]) {
        return Err(invalid(
            "bounds",
            format!("{lo:?}..{hi:?}"),
            "must be a non-empty box",
        ));
    }
    let h = extent / resolution as f64;
    let dims: [usize; 3] = [0, 1, 2].map(|k| ((hi[k] - lo[k]) / h).ceil() as usize + 1);
    let node = |i: usize, j: usize, k: usize| (k * dims[1] + j) * dims[0] + i;
    let pos = |i: usize, j: usize, k: usize| {
        [
            lo[0] + i as f64 * h,
            lo[1] + j as f64 * h,
            lo[2] + k as f64 * h,
        ]
    };
    let plane = dims[0] * dims[1];
    let values: Vec<f64> = (0..plane * dims[2])
        .into_par_iter()
        .map(|n| {
            let (i, j, k) = (n % dims[0], (n / dims[0]) % dims[1], n / plane);
            let v = sdf(pos(i, j, k));
            // Nodes on the grid boundary count as outside, so the mesh is always closed
            // (a shape larger than the box is cut flat by its faces).
            let border = i == 0
                || j == 0
                || k == 0
                || i + 1 == dims[0]
                || j + 1 == dims[1]
                || k + 1 == dims[2];
            if border { v.max(h * 1e-3) } else { v }
        })
        .collect();
    if let Some(n) = values.iter().position(|v| !v.is_finite()) {
        return Err(invalid(
            "sdf",
            n,
            "returned a non-finite value at this grid node",
        ));
    }
    // Per z-slab: triangles as edge keys, and (key, position) of their vertices.
    type Slab = (Vec<[u64; 3]>, Vec<(u64, V3)>);
    let slabs: Vec<Slab> = (0..dims[2] - 1)
        .into_par_iter()
        .map(|k| {
            let mut tris = Vec::new();
            let mut verts = Vec::new();
            for j in 0..dims[1] - 1 {
                for i in 0..dims[0] - 1 {
                    let corner = |c: u8| {
                        let (di, dj, dk) = (
                            (c & 1) as usize,
                            ((c >> 1) & 1) as usize,
                            ((c >> 2) & 1) as usize,
                        );
                        (node(i + di, j + dj, k + dk), pos(i + di, j + dj, k + dk))
                    };
                    let cube: [(usize, V3); 8] = std::array::from_fn(|c| corner(c as u8));
                    let inside = cube.iter().filter(|(n, _)| values[*n] < 0.0).count();
                    if inside == 0 || inside == 8 {
                        continue;
                    }
                    for tet in KUHN {
                        polygonise(&tet, &cube, &values, &mut tris, &mut verts);
                    }
                }
            }
            (tris, verts)
        })
        .collect();
    let mut all_verts: Vec<(u64, V3)> = slabs.iter().flat_map(|s| s.1.iter().copied()).collect();
    all_verts.par_sort_unstable_by_key(|v| v.0);
    all_verts.dedup_by_key(|v| v.0);
    let index_of = |key: u64| {
        all_verts
            .binary_search_by_key(&key, |v| v.0)
            .map(|i| i as u32)
            .unwrap_or(0)
    };
    let triangles: Vec<[u32; 3]> = slabs
        .par_iter()
        .flat_map_iter(|s| s.0.iter().map(|t| t.map(index_of)))
        .collect();
    let vertices = all_verts.iter().map(|v| to_f32(v.1)).collect();
    Ok(TriMesh::new(vertices, triangles)?)
}

/// Emits the 0, 1 or 2 triangles of one tetrahedron.
fn polygonise(
    tet: &[u8; 4],
    cube: &[(usize, V3); 8],
    values: &[f64],
    tris: &mut Vec<[u64; 3]>,
    verts: &mut Vec<(u64, V3)>,
) {
    let c = tet.map(|t| cube[t as usize]);
    let f = c.map(|(n, _)| values[n]);
    let inside: Vec<usize> = (0..4).filter(|&a| f[a] < 0.0).collect();
    let outside: Vec<usize> = (0..4).filter(|&a| f[a] >= 0.0).collect();
    let mut edge = |a: usize, b: usize| -> (u64, V3) {
        // a inside, b outside; key by (lower node, direction bits).
        let (na, nb) = (c[a].0, c[b].0);
        let (lo_c, hi_c) = if na < nb {
            (tet[a], tet[b])
        } else {
            (tet[b], tet[a])
        };
        let key = ((na.min(nb) as u64) << 3) | u64::from(hi_c ^ lo_c);
        let t = (f[a] / (f[a] - f[b])).clamp(1e-3, 1.0 - 1e-3);
        let p = [0, 1, 2].map(|k| c[a].1[k] + t * (c[b].1[k] - c[a].1[k]));
        verts.push((key, p));
        (key, p)
    };
    let polys: Vec<Vec<(u64, V3)>> = match (inside.len(), outside.len()) {
        (1, 3) => vec![outside.iter().map(|&o| edge(inside[0], o)).collect()],
        (3, 1) => vec![inside.iter().map(|&i| edge(i, outside[0])).collect()],
        (2, 2) => {
            let (i0, i1, o0, o1) = (inside[0], inside[1], outside[0], outside[1]);
            let q = [edge(i0, o0), edge(i0, o1), edge(i1, o1), edge(i1, o0)];
            vec![vec![q[0], q[1], q[2]], vec![q[0], q[2], q[3]]]
        }
        _ => Vec::new(),
    };
    let centroid = |idx: &[usize]| {
        let mut s = [0.0; 3];
        for &a in idx {
            for (acc, x) in s.iter_mut().zip(c[a].1) {
                *acc += x / idx.len() as f64;
            }
        }
        s
    };
    let outward = sub(centroid(&outside), centroid(&inside));
    for poly in polys {
        let [a, b, d] = [poly[0], poly[1], poly[2]];
        let n = cross(sub(b.1, a.1), sub(d.1, a.1));
        if dot(n, outward) >= 0.0 {
            tris.push([a.0, b.0, d.0]);
        } else {
            tris.push([a.0, d.0, b.0]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshgnn_geometry::mesh_report;

    #[test]
    fn torus_is_closed_genus_one() {
        let torus = |p: V3| {
            let q = ((p[0] * p[0] + p[1] * p[1]).sqrt() - 1.0, p[2]);
            (q.0 * q.0 + q.1 * q.1).sqrt() - 0.35
        };
        let mesh = marching_tetrahedra(&torus, [-1.5, -1.5, -0.5], [1.5, 1.5, 0.5], 40).unwrap();
        let r = mesh_report(&mesh);
        assert!(r.watertight && r.edge_manifold && r.vertex_manifold);
        // Euler characteristic V − E + F = 0 for a torus.
        assert_eq!(r.vertices as i64 - r.edges as i64 + r.faces as i64, 0);
        // Outward orientation: signed volume ≈ 2π²Rr² = 2.418.
        let mut vol = 0.0;
        for f in 0..mesh.face_count() {
            let [a, b, c] = mesh.triangle_positions(f).map(crate::vec3::to_f64);
            vol += dot(a, cross(b, c)) / 6.0;
        }
        assert!(
            (vol - 2.0 * std::f64::consts::PI.powi(2) * 0.35 * 0.35).abs() < 0.1,
            "{vol}"
        );
    }
}
