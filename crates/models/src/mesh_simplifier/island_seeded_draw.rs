//! The point sampler's draw on a mesh, refined for the nearest-seed dual (beyond the thesis):
//! where the surface folds back near itself, a drawn vertex's nearest-seed region can hold a
//! piece joined to it only through other regions, and the dual is no surface there
//! ([`meshgnn_geometry::island_seeds`]). Every sizeable such piece gets a seed of its own,
//! and the draw is shortened by as many so the vertex count stays near the target.

use meshgnn_geometry::{TriMesh, island_seeds};

use super::SampledPoints;
use crate::Result;

/// A cut-off piece gets a seed when it holds at least `1 / ISLAND_FRACTION` of a region's
/// mean vertex count (and at least one vertex): 8 measured best of 2, 4 and 8, and a floor of
/// one vertex better than two (docs/mesh_simplifier_model.md, "Connected regions and island
/// seeds").
pub const ISLAND_FRACTION: usize = 8;

/// `sampled`, a draw of `target` of `surface`'s vertices, refined: when its pieces call for
/// `k > 0` island seeds, the draw is repeated for `max(target − k, target / 2)` vertices with
/// the same probabilities and seed, and that draw's island seeds are appended to it (the
/// floor keeps a mesh of more components and cut-off pieces than its target from losing most
/// of its draw). With no island seed the draw comes back as it was. The probabilities are
/// kept.
pub fn with_island_seeds(
    sampled: SampledPoints,
    surface: &TriMesh,
    target: usize,
    seed: u64,
) -> Result<SampledPoints> {
    let min_vertices = (surface.vertex_count() / (target.max(1) * ISLAND_FRACTION)).max(1);
    let extra =
        island_seeds(surface, &sampled.indices, min_vertices)?.len() - sampled.indices.len();
    if extra == 0 {
        return Ok(sampled);
    }
    let redrawn = target.saturating_sub(extra).max(target / 2).max(1);
    let weights: Vec<f32> = sampled.probabilities.detach().to_vec1()?;
    let fewer = meshgnn_graph::balanced_sampling(surface.vertices(), &weights, redrawn, seed)?;
    Ok(SampledPoints {
        indices: island_seeds(surface, &fewer, min_vertices)?,
        ..sampled
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::{Device, Tensor};

    fn drawn(indices: Vec<u32>, weights: &[f32]) -> SampledPoints {
        SampledPoints {
            indices,
            probabilities: Tensor::new(weights, &Device::Cpu).unwrap(),
        }
    }

    /// Two unit squares of 5 × 5 vertices in the plane z = 0, the second at x ∈ [2, 3]
    /// (vertices 25-49, its centre (2.5, 0.5) vertex 37).
    fn two_squares() -> TriMesh {
        let square = meshgnn_geometry::grid_plane(4, 4);
        let shifted = square.vertices().iter().map(|p| [p[0] + 2.0, p[1], p[2]]);
        let second = square.triangles().iter().map(|t| t.map(|c| c + 25));
        TriMesh::new(
            square.vertices().iter().copied().chain(shifted).collect(),
            square.triangles().iter().copied().chain(second).collect(),
        )
        .unwrap()
    }

    #[test]
    fn a_cut_off_piece_takes_a_drawn_vertex_s_place() {
        // Drawn on the first square only: (0, 0), (1, 1) and (0.5, 0.5). The whole second
        // square is nearest (1, 1), a piece of its region joined to it by no edge.
        let squares = two_squares();
        let (a, b, c, centre) = (0, 24, 12, 37);
        let mut weights = vec![1e-6f32; 50];
        weights[a as usize] = 1.0;
        weights[b as usize] = 1.0;
        // One island seed for a target of 3: the draw is repeated for 2 (the two heavy
        // vertices), and the second square gets its centre.
        let refined = with_island_seeds(drawn(vec![a, b, c], &weights), &squares, 3, 0).unwrap();
        let mut sorted = refined.indices.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, vec![a, b, centre]);
        assert_eq!(refined.indices[2], centre);
        // As many island seeds as the target: the draw is repeated for half the target (at
        // least one vertex), here (0, 0) again, the heavy one, and the seed added above it.
        weights[b as usize] = 1e-6;
        let refined = with_island_seeds(drawn(vec![a], &weights), &squares, 1, 0).unwrap();
        assert_eq!(refined.indices, vec![a, centre]);
        // Nothing cut off: the draw as it was.
        let refined = with_island_seeds(drawn(vec![a, centre], &weights), &squares, 2, 0).unwrap();
        assert_eq!(refined.indices, vec![a, centre]);
    }
}
