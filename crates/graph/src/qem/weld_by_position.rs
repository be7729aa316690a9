//! Welding of vertices that share an exact position (unwelded triangle soups, as STL-like
//! exporters write them, meshes split on attribute seams, patch models whose patches meet
//! at copied vertices), before QEM decimation and before the neural simplifier
//! ([`weld_coincident_vertices`]).
//!
//! Vertices are merged when their positions are bit-identical (with `-0.0 == 0.0`) and, when
//! texture coordinates are given, their UVs are bit-identical too: vertices at one position with
//! different UVs stay apart and are flagged as *seam* vertices, linked to their twins, which
//! decimation moves only together so that textures do not tear.

use meshgnn_geometry::TriMesh;
use rayon::prelude::*;

use crate::Result;

/// The result of [`weld_by_position`].
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Welding {
    /// `#V`: the welded vertex each original vertex became.
    pub map: Vec<u32>,
    /// `#W`: the first original vertex of each welded vertex (welded ids follow its order).
    pub representatives: Vec<u32>,
    /// `#W`: true when another welded vertex has the same position (a UV seam).
    pub seam: Vec<bool>,
    /// `#W`: the next welded vertex at the same position, in a cycle through all of them
    /// (itself when it is alone there).
    pub twin: Vec<u32>,
}

impl Welding {
    /// True when at least two vertices were merged.
    pub fn merged_any(&self) -> bool {
        self.representatives.len() < self.map.len()
    }
}

/// The other vertices at the position of `v`, following the cycle `twin` (of [`Welding`]).
pub(crate) fn twins_of(twin: &[u32], v: u32) -> impl Iterator<Item = u32> + '_ {
    std::iter::successors(Some(twin[v as usize]), move |&t| Some(twin[t as usize]))
        .take_while(move |&t| t != v)
}

/// The bit pattern of a coordinate with `-0.0` folded onto `0.0`.
fn key(x: f32) -> u32 {
    if x == 0.0 { 0 } else { x.to_bits() }
}

/// Welds `vertices: #V×3` by exact position (and exact `uvs: #V×2` when given).
/// O(V log V), parallel sort; deterministic.
pub(crate) fn weld_by_position(vertices: &[[f32; 3]], uvs: Option<&[[f32; 2]]>) -> Welding {
    let uv_key = |i: usize| -> [u32; 2] {
        uvs.and_then(|u| u.get(i))
            .map_or([0, 0], |uv| [key(uv[0]), key(uv[1])])
    };
    let mut order: Vec<([u32; 3], [u32; 2], u32)> = vertices
        .par_iter()
        .enumerate()
        .map(|(i, p)| ([key(p[0]), key(p[1]), key(p[2])], uv_key(i), i as u32))
        .collect();
    // Keys plus index are unique, so the unstable sort is deterministic.
    order.par_sort_unstable();

    let n = vertices.len();
    let mut representative = vec![0u32; n];
    let mut seam_original = vec![false; n];
    // The next representative at the same position (cyclic), for representatives only.
    let mut next_original: Vec<u32> = (0..n as u32).collect();
    let mut reps_here: Vec<u32> = Vec::new();
    let mut start = 0;
    while start < order.len() {
        let pos = order[start].0;
        let mut end = start;
        while end < order.len() && order[end].0 == pos {
            end += 1;
        }
        let group = &order[start..end];
        let several_uvs = group.iter().any(|g| g.1 != group[0].1);
        let mut k = 0;
        reps_here.clear();
        while k < group.len() {
            let rep = group[k].2;
            reps_here.push(rep);
            let mut m = k;
            while m < group.len() && group[m].1 == group[k].1 {
                representative[group[m].2 as usize] = rep;
                seam_original[group[m].2 as usize] = several_uvs;
                m += 1;
            }
            k = m;
        }
        for (i, &r) in reps_here.iter().enumerate() {
            next_original[r as usize] = reps_here[(i + 1) % reps_here.len()];
        }
        start = end;
    }

    let mut map = vec![0u32; n];
    let mut representatives = Vec::new();
    let mut seam = Vec::new();
    for i in 0..n {
        let rep = representative[i] as usize;
        if rep == i {
            map[i] = representatives.len() as u32;
            representatives.push(i as u32);
            seam.push(seam_original[i]);
        } else {
            // The representative is the smallest index of its group, already assigned.
            map[i] = map[rep];
        }
    }
    let twin = representatives
        .iter()
        .map(|&r| map[next_original[r as usize] as usize])
        .collect();
    Welding {
        map,
        representatives,
        seam,
        twin,
    }
}

/// A mesh with its coincident vertices merged ([`weld_coincident_vertices`]).
#[derive(Debug, Clone, PartialEq)]
pub struct WeldedMesh {
    /// One vertex per distinct position, in the order of first occurrence; the faces
    /// renumbered, those left with a repeated corner or on the same three vertices as an
    /// earlier face dropped. Other attributes are not carried.
    pub mesh: TriMesh,
    /// `#W`: the input vertex each welded vertex stands for (its first at that position).
    pub representatives: Vec<u32>,
}

/// Merges the vertices of `mesh` with bit-identical positions (`-0.0 == 0.0`), so that
/// surfaces stored as separate patches or as a triangle soup are connected where they
/// meet; `None` when every position is already distinct. O(V log V + F); deterministic.
///
/// ```
/// use meshgnn_geometry::TriMesh;
/// use meshgnn_graph::weld_coincident_vertices;
/// // Two triangles sharing an edge, stored with the edge's vertices copied.
/// let v = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
/// let mesh = TriMesh::new(v, vec![[0, 1, 2], [3, 5, 4]])?;
/// let welded = weld_coincident_vertices(&mesh)?.expect("two positions are copied");
/// assert_eq!(welded.mesh.triangles(), &[[0, 1, 2], [1, 3, 2]]);
/// assert_eq!(welded.representatives, vec![0, 1, 2, 5]);
/// assert_eq!(weld_coincident_vertices(&welded.mesh)?, None);
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn weld_coincident_vertices(mesh: &TriMesh) -> Result<Option<WeldedMesh>> {
    let welding = weld_by_position(mesh.vertices(), None);
    if !welding.merged_any() {
        return Ok(None);
    }
    let positions = welding
        .representatives
        .iter()
        .map(|&r| mesh.vertices()[r as usize])
        .collect();
    let triangles = mesh
        .triangles()
        .par_iter()
        .map(|t| t.map(|v| welding.map[v as usize]))
        .collect();
    Ok(Some(WeldedMesh {
        mesh: TriMesh::new(positions, triangles)?.without_degenerate_faces(),
        representatives: welding.representatives,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welds_duplicates_and_flags_uv_seams() {
        let v = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [-0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
        ];
        let w = weld_by_position(&v, None);
        assert_eq!(w.map, vec![0, 1, 0, 1, 2]);
        assert_eq!(w.representatives, vec![0, 1, 4]);
        assert!(w.merged_any());
        assert_eq!(w.seam, vec![false; 3]);

        let uv = vec![[0.0, 0.0], [0.5, 0.0], [0.0, 0.0], [0.7, 0.0], [1.0, 1.0]];
        let w = weld_by_position(&v, Some(&uv));
        assert_eq!(w.map, vec![0, 1, 0, 2, 3]);
        assert_eq!(w.seam, vec![false, true, true, false]);
        assert_eq!(w.twin, vec![0, 2, 1, 3]);
    }

    #[test]
    fn welded_patches_share_their_seam_and_lose_collapsed_faces() {
        // A unit square as two patches (copied seam vertices 1 = 3 and 2 = 4), plus a sliver
        // whose corners 2 and 6 coincide and a copy of the first face over copied vertices.
        let v = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [-0.0, 0.0, 0.0],
        ];
        let faces = vec![[0, 1, 2], [3, 5, 4], [2, 6, 5], [7, 3, 4]];
        let welded = weld_coincident_vertices(&TriMesh::new(v, faces).unwrap())
            .unwrap()
            .unwrap();
        assert_eq!(welded.representatives, vec![0, 1, 2, 5]);
        assert_eq!(
            welded.mesh.vertices(),
            &[
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [1.0, 1.0, 0.0]
            ]
        );
        assert_eq!(welded.mesh.triangles(), &[[0, 1, 2], [1, 3, 2]]);
    }
}
