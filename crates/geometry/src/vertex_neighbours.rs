//! A mesh's vertex one-rings as compressed rows, for the walks over its edges (breadth first,
//! Dijkstra) in this crate.

use crate::tri_mesh::TriMesh;

/// Each vertex's neighbours along mesh edges, in compressed rows, in face order (an edge of
/// two faces is listed twice; the graph walks over it do not mind).
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
        Self { start, list }
    }

    pub(crate) fn of(&self, v: u32) -> &[u32] {
        &self.list[self.start[v as usize]..self.start[v as usize + 1]]
    }
}
