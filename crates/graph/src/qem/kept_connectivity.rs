//! The QEM connectivity of chosen vertices on a surface (beyond the thesis, for the neural
//! mesh simplifier of ch. 6): every other vertex collapses onto them at input positions, so
//! the faces left join exactly the chosen vertices, closed where the surface is closed
//! (docs/mesh_simplifier_model.md, "Small parts rebuilt by QEM" and "Curled parts folded
//! closed").

use meshgnn_geometry::{PartSurface, TriMesh};

use super::decimation::{DecimationOptions, Target, decimate_keeping};
use super::held_vertex_folding::fold_held_vertices;
use crate::error::Result;

/// The surface [`decimate_keeping`] leaves of the surface `faces` (over `vertices`) when every
/// vertex but `keep` may collapse onto them at its input position (`keep_original_positions`,
/// a target of one face): faces over local indices, `i < keep.len()` naming `keep[i]` and
/// later ones the vertices the manifold, flip and fold checks held (`extra`, at their input
/// positions). When more than `max_extra` are held, held vertices collapse further under the
/// link condition alone, letting faces fold, until `max_extra` remain (a part that curls).
/// `None` when more are left or no face is.
///
/// Errors when a face or `keep` names a vertex `vertices` lacks.
///
/// ```
/// use meshgnn_geometry::icosphere;
/// use meshgnn_graph::kept_vertex_connectivity;
/// let sphere = icosphere(1); // 42 vertices
/// let kept = [0, 1, 2, 3, 4, 5];
/// let surface = kept_vertex_connectivity(sphere.vertices(), sphere.triangles(), &kept, 0)?;
/// // Six vertices of a closed surface: the eight faces of an octahedron-like solid.
/// assert_eq!(surface.map(|s| s.faces.len()), Some(8));
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn kept_vertex_connectivity(
    vertices: &[[f32; 3]],
    faces: &[[u32; 3]],
    keep: &[u32],
    max_extra: usize,
) -> Result<Option<PartSurface>> {
    // The surface alone, its vertices renumbered in order of first use.
    let mut local = vec![u32::MAX; vertices.len()];
    let mut positions = Vec::new();
    let mut renumber = |v: u32| -> u32 {
        match local.get_mut(v as usize) {
            Some(slot) => {
                if *slot == u32::MAX {
                    *slot = positions.len() as u32;
                    positions.push(vertices[v as usize]);
                }
                *slot
            }
            None => u32::MAX,
        }
    };
    let part_faces: Vec<[u32; 3]> = faces.iter().map(|t| t.map(&mut renumber)).collect();
    let keep_local: Vec<u32> = keep.iter().map(|&v| renumber(v)).collect();
    let surface = TriMesh::new(positions, part_faces)?;
    let options = DecimationOptions {
        target: Target::Faces(1),
        keep_original_positions: true,
        ..Default::default()
    };
    let out = decimate_keeping(&surface, &options, &keep_local, &mut |_| {})?;
    let mut held = vec![true; out.mesh.vertex_count()];
    for &v in &keep_local {
        held[out.vertex_map[v as usize] as usize] = false;
    }
    let mut faces = out.mesh.triangles().to_vec();
    fold_held_vertices(out.mesh.vertices(), &mut faces, &mut held, max_extra);
    // Output vertex → local index: the kept ones first, then the held ones in output order.
    let mut index = vec![u32::MAX; out.mesh.vertex_count()];
    for (i, &v) in keep_local.iter().enumerate() {
        index[out.vertex_map[v as usize] as usize] = i as u32;
    }
    let mut extra = Vec::new();
    for (o, slot) in index.iter_mut().enumerate() {
        if held[o] {
            *slot = (keep.len() + extra.len()) as u32;
            extra.push(out.mesh.vertices()[o]);
        }
    }
    if faces.is_empty() || extra.len() > max_extra {
        return Ok(None);
    }
    Ok(Some(PartSurface {
        faces: faces.iter().map(|t| t.map(|v| index[v as usize])).collect(),
        extra,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshgnn_geometry::{icosphere, is_edge_manifold, is_watertight};

    /// The surface over `keep`'s positions followed by its extra vertices.
    fn as_mesh(vertices: &[[f32; 3]], keep: &[u32], surface: &PartSurface) -> TriMesh {
        let positions = keep
            .iter()
            .map(|&v| vertices[v as usize])
            .chain(surface.extra.iter().copied())
            .collect();
        TriMesh::new(positions, surface.faces.clone()).unwrap()
    }

    #[test]
    fn every_other_vertex_of_a_closed_surface_collapses_onto_the_kept_ones() {
        let sphere = icosphere(2); // 162 vertices
        let keep: Vec<u32> = (0..162).step_by(9).collect();
        let surface = kept_vertex_connectivity(sphere.vertices(), sphere.triangles(), &keep, 0)
            .unwrap()
            .expect("every other vertex collapses");
        assert!(surface.extra.is_empty());
        // A closed genus-0 surface over k vertices has 2k - 4 faces.
        assert_eq!(surface.faces.len(), 2 * keep.len() - 4);
        let closed = as_mesh(sphere.vertices(), &keep, &surface);
        assert!(is_watertight(&closed) && is_edge_manifold(&closed));
    }

    #[test]
    fn a_surface_given_among_other_vertices_is_taken_alone() {
        // The sphere's faces over vertex numbers shifted past 100 unused vertices.
        let sphere = icosphere(1);
        let mut vertices = vec![[9.0f32; 3]; 100];
        vertices.extend_from_slice(sphere.vertices());
        let faces: Vec<[u32; 3]> = sphere
            .triangles()
            .iter()
            .map(|t| t.map(|v| v + 100))
            .collect();
        let keep = [100u32, 101, 102, 103, 104, 105];
        let shifted = kept_vertex_connectivity(&vertices, &faces, &keep, 0).unwrap();
        let plain = kept_vertex_connectivity(
            sphere.vertices(),
            sphere.triangles(),
            &[0, 1, 2, 3, 4, 5],
            0,
        )
        .unwrap();
        assert_eq!(shifted, plain);
        assert!(shifted.is_some());
    }

    #[test]
    fn held_vertices_come_back_as_extras_up_to_the_bound() {
        let sphere = icosphere(1);
        let keep = [0u32, 1];
        // Two kept vertices cannot close a surface: at least two others must stay.
        assert_eq!(
            kept_vertex_connectivity(sphere.vertices(), sphere.triangles(), &keep, 0).unwrap(),
            None
        );
        let surface = kept_vertex_connectivity(sphere.vertices(), sphere.triangles(), &keep, 40)
            .unwrap()
            .expect("with room for extras");
        assert!(surface.extra.len() >= 2);
        // Every extra is an input vertex, where it was.
        for p in &surface.extra {
            assert!(sphere.vertices().contains(p));
        }
        let closed = as_mesh(sphere.vertices(), &keep, &surface);
        assert!(is_watertight(&closed) && is_edge_manifold(&closed));
        let bound = surface.extra.len() - 1;
        assert_eq!(
            kept_vertex_connectivity(sphere.vertices(), sphere.triangles(), &keep, bound).unwrap(),
            None
        );
    }

    #[test]
    fn indices_outside_the_vertices_are_errors() {
        let sphere = icosphere(1);
        assert!(
            kept_vertex_connectivity(sphere.vertices(), sphere.triangles(), &[999], 0).is_err()
        );
        assert!(kept_vertex_connectivity(sphere.vertices(), &[[0, 1, 999]], &[0], 0).is_err());
    }
}
