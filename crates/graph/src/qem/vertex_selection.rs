//! QEM as a point-selection baseline (thesis ch. 5.5, Table 5.1 "QEM"): decimate a mesh with
//! every surviving vertex kept at an original position until exactly the requested number of
//! vertices is left, and report which input vertices those are.

use meshgnn_geometry::{TriMesh, boundary_loops};

use super::decimation::{DecimationOptions, Target, decimate};
use crate::error::{Error, Result};

/// Passes before giving up (each removes at least half of the remaining excess).
const MAX_PASSES: usize = 64;

/// The indices (into `mesh.vertices()`) of the `count` vertices QEM keeps, plus the decimated
/// mesh: its vertex `o` sits at input vertex `indices[o]`.
pub struct QemVertices {
    /// Kept input vertices (distinct), in the decimated mesh's vertex order.
    pub indices: Vec<u32>,
    /// The decimated mesh.
    pub mesh: TriMesh,
}

/// Decimates `mesh` with `keep_original_positions` to exactly `count` vertices (`mesh` is a
/// manifold mesh whose vertices are all referenced).
///
/// A collapse removes one vertex and one (boundary) or two (interior) faces, so a pass that
/// removes `2e − B` faces (`e` excess vertices, `B` boundary vertices) removes at most `e`
/// vertices; passes repeat until the count is met. Fails when QEM cannot collapse further
/// (non-manifold or tiny input) or when an input vertex is unreferenced.
pub fn qem_vertices(mesh: &TriMesh, count: usize) -> Result<QemVertices> {
    let mut current = mesh.clone();
    // origin[o]: the input vertex that the current vertex `o` sits at.
    let mut origin: Vec<u32> = (0..mesh.vertex_count() as u32).collect();
    for _ in 0..MAX_PASSES {
        let vertices = current.vertex_count();
        if vertices <= count {
            break;
        }
        let excess = vertices - count;
        let boundary: usize = boundary_loops(&current).iter().map(Vec::len).sum();
        let remove = (2 * excess).saturating_sub(boundary).max(1);
        let target = current.face_count().saturating_sub(remove).max(1);
        let out = decimate(
            &current,
            &DecimationOptions {
                target: Target::Faces(target),
                keep_original_positions: true,
                ..Default::default()
            },
        )?;
        if out.mesh.vertex_count() >= vertices {
            return Err(Error::UnusableMesh {
                what: "QEM vertex selection".into(),
                message: format!(
                    "QEM cannot remove more vertices ({} left of {}, {}): use another method",
                    vertices,
                    mesh.vertex_count(),
                    out.stop_reason.as_str()
                ),
            });
        }
        let mut next = vec![u32::MAX; out.mesh.vertex_count()];
        for (i, &o) in out.vertex_map.iter().enumerate() {
            let slot = next.get_mut(o as usize);
            if let (Some(slot), Some(&src), Some(p), Some(q)) = (
                slot,
                origin.get(i),
                current.vertices().get(i),
                out.mesh.vertices().get(o as usize),
            ) && *slot == u32::MAX
                && p == q
            {
                *slot = src;
            }
        }
        if next.contains(&u32::MAX) {
            return Err(Error::UnusableMesh {
                what: "QEM vertex selection".into(),
                message:
                    "QEM produced a vertex at no input position (unreferenced or welded input)"
                        .into(),
            });
        }
        origin = next;
        current = out.mesh;
    }
    if current.vertex_count() != count {
        return Err(Error::UnusableMesh {
            what: "QEM vertex selection".into(),
            message: format!(
                "QEM stopped at {} vertices instead of {count}: use another method",
                current.vertex_count()
            ),
        });
    }
    let mut distinct = origin.clone();
    distinct.sort_unstable();
    distinct.dedup();
    if distinct.len() != count {
        return Err(Error::UnusableMesh {
            what: "QEM vertex selection".into(),
            message: "QEM mapped two kept vertices to the same input vertex".into(),
        });
    }
    Ok(QemVertices {
        indices: origin,
        mesh: current,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshgnn_geometry::icosphere;

    #[test]
    fn keeps_exactly_the_requested_input_vertices() {
        let mesh = icosphere(3);
        let kept = qem_vertices(&mesh, 100).unwrap();
        assert_eq!(kept.indices.len(), 100);
        assert_eq!(kept.mesh.vertex_count(), 100);
        for (o, &i) in kept.indices.iter().enumerate() {
            assert_eq!(kept.mesh.vertices()[o], mesh.vertices()[i as usize]);
        }
        let mut distinct = kept.indices.clone();
        distinct.sort_unstable();
        distinct.dedup();
        assert_eq!(distinct.len(), 100);
    }
}
