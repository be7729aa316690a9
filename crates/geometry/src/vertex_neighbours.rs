//! A mesh's vertex one-rings as compressed rows, for the walks over its edges (breadth first,
//! Dijkstra) in this crate.

use crate::tri_mesh::TriMesh;

/// Each vertex's neighbours along mesh edges, in compressed rows, each once, in the order of
/// the first face that names the edge (a walk over them visits what it would visit over every
/// face's edges, and a Dijkstra relaxes each edge once instead of twice).
pub(crate) struct VertexNeighbours {
    start: Vec<usize>,
    list: Vec<u32>,
}

impl VertexNeighbours {
    pub(crate) fn new(mesh: &TriMesh) -> Self {
        let mut start = vec![0usize; mesh.vertex_count() + 1];
        for t in mesh.triangles() {
            for &c in t {
                start[c as usize + 1] += 2;
            }
        }
        for i in 1..start.len() {
            start[i] += start[i - 1];
        }
        let mut fill = start.clone();
        let mut list = vec![0u32; start[start.len() - 1]];
        for t in mesh.triangles() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                for (from, to) in [(a, b), (b, a)] {
                    list[fill[from as usize]] = to;
                    fill[from as usize] += 1;
                }
            }
        }
        // Each row keeps the first occurrence of every neighbour, compacted in place (rows hold
        // about twelve entries, six distinct, on a closed mesh).
        let mut kept = 0;
        let mut row_start = 0;
        for v in 0..mesh.vertex_count() {
            let row_end = start[v + 1];
            let first = kept;
            for i in row_start..row_end {
                let w = list[i];
                if !list[first..kept].contains(&w) {
                    list[kept] = w;
                    kept += 1;
                }
            }
            row_start = row_end;
            start[v + 1] = kept;
        }
        list.truncate(kept);
        Self { start, list }
    }

    pub(crate) fn of(&self, v: u32) -> &[u32] {
        &self.list[self.start[v as usize]..self.start[v as usize + 1]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_list_each_neighbour_once_in_first_face_order() {
        // Two triangles sharing the edge 1-2, and a third face repeating the first one's edge
        // 0-1 the other way round.
        let mesh = TriMesh::new(
            vec![
                [0.0; 3],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
            ],
            vec![[0, 1, 2], [2, 1, 3], [1, 0, 4]],
        )
        .unwrap();
        let rows = VertexNeighbours::new(&mesh);
        // Face order: 0-1, 1-2, 2-0 of the first face, then 2-1, 1-3, 3-2, then 1-0, 0-4, 4-1.
        assert_eq!(rows.of(0), [1, 2, 4]);
        assert_eq!(rows.of(1), [0, 2, 3, 4]);
        assert_eq!(rows.of(2), [1, 0, 3]);
        assert_eq!(rows.of(3), [1, 2]);
        assert_eq!(rows.of(4), [0, 1]);
    }
}
