//! Seeds moved from where they are cheapest to drop to where the surface fits its regions
//! worst: the budget of a vertex-selecting simplifier (the neural mesh simplifier of thesis
//! ch. 6) reallocated by quadric error, as QEM's greedy collapses allocate theirs. A draw
//! by probability gives every stretch of surface about as many vertices as its density asks:
//! a coarse part of few, large faces (a low-poly model's body) keeps too few corners while a
//! finely tessellated, nearly flat one keeps more than it needs. Each seed stands for its
//! geodesic Voronoi region ([`SeedRegions`]: those of the seeds before
//! [`super::region_quadric_vertices`] settled them, which they stay inside), whose faces'
//! summed plane quadric `Q_r` measures how well the seed alone represents it (Garland &
//! Heckbert's error of collapsing the region onto it):
//! - the **fit** of region `r` is `Q_r(seed_r)`;
//! - its **drop cost** is the least increase when a neighbouring seed `t` takes it over,
//!   `min_t Q_r(seed_t) − Q_r(seed_r)`;
//! - splitting a region at its worst-fitting vertex (the largest `Q_r(v)`) is estimated to
//!   save half its fit.
//!
//! The cheapest drops pair with the worst fits while the saving exceeds the cost; a dropped
//! region never touches another dropped or a split one, so each estimate stays valid for the
//! round. The count stays, a region without a neighbour (an island's only seed) is never
//! dropped, a connected component with fewer than `MIN_COMPONENT_SEEDS` seeds neither gives
//! nor takes one, and the seeds stay distinct. [`super::region_quadric_vertices`] then settles
//! the moved seeds on their new regions' best-fitting vertices.

use meshgnn_geometry::vec3::to_f64;
use meshgnn_geometry::{MIN_COMPONENT_SEEDS, TriMesh, connected_components};

use super::seed_regions::SeedRegions;
use crate::error::Result;

/// Share of a region's fit a split is estimated to save.
const SPLIT_SAVING: f64 = 0.5;

/// `seeds` after one round of exchanges (module docs) on `regions` (built from these seeds
/// or from seeds each inside the region it names): the seeds of the regions cheapest to drop
/// replaced, in place, by the worst-fitting vertices of the regions that fit worst. Errors
/// when the seeds do not match the regions, are out of range or repeated.
///
/// ```
/// use meshgnn_geometry::grid_plane;
/// use meshgnn_graph::{SeedRegions, region_seed_exchange};
/// // A flat square fits every region exactly: nothing to gain, every seed stays.
/// let square = grid_plane(6, 6);
/// let seeds = [0, 20, 48];
/// let regions = SeedRegions::new(&square, &seeds)?;
/// assert_eq!(region_seed_exchange(&square, &regions, &seeds)?, seeds);
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn region_seed_exchange(
    input: &TriMesh,
    regions: &SeedRegions,
    seeds: &[u32],
) -> Result<Vec<u32>> {
    let seed_of = regions.seed_of_vertex(input, seeds)?;
    let (region, quadrics) = (regions.region(), regions.quadrics());
    let position = |v: u32| to_f64(input.vertices()[v as usize]);
    let fit: Vec<f64> = (0..seeds.len())
        .map(|r| quadrics[r].evaluate(position(seeds[r])))
        .collect();
    // Worst-fitting vertex of each region, not a seed: where a split would put its new seed.
    let mut worst: Vec<(f64, u32)> = vec![(f64::NEG_INFINITY, u32::MAX); seeds.len()];
    for (v, &r) in region.iter().enumerate() {
        if let Some(w) = worst.get_mut(r as usize)
            && seed_of[v] == u32::MAX
        {
            let e = quadrics[r as usize].evaluate(position(v as u32));
            if e > w.0 {
                *w = (e, v as u32);
            }
        }
    }
    // Drop cost and neighbours, from the edges between regions.
    let mut drop_cost = vec![f64::INFINITY; seeds.len()];
    let mut neighbours: Vec<Vec<u32>> = vec![Vec::new(); seeds.len()];
    for t in input.triangles() {
        for k in 0..3 {
            let (a, b) = (region[t[k] as usize], region[t[(k + 1) % 3] as usize]);
            if a == b || a == u32::MAX || b == u32::MAX {
                continue;
            }
            for (r, other) in [(a, b), (b, a)] {
                let r = r as usize;
                let cost = quadrics[r].evaluate(position(seeds[other as usize])) - fit[r];
                drop_cost[r] = drop_cost[r].min(cost);
                if !neighbours[r].contains(&other) {
                    neighbours[r].push(other);
                }
            }
        }
    }
    let (components, component) = connected_components(input);
    // One more slot for the seeds on unreferenced vertices (never dropped: no neighbours).
    let mut component_seeds = vec![0usize; components + 1];
    let slot = |v: u32| (component[v as usize] as usize).min(components);
    for &s in seeds {
        component_seeds[slot(s)] += 1;
    }
    let mut cheapest: Vec<usize> = (0..seeds.len())
        .filter(|&r| drop_cost[r].is_finite())
        .collect();
    cheapest.sort_by(|&a, &b| drop_cost[a].total_cmp(&drop_cost[b]).then(a.cmp(&b)));
    let mut worst_fitting: Vec<usize> = (0..seeds.len())
        .filter(|&r| worst[r].1 != u32::MAX)
        .collect();
    worst_fitting.sort_by(|&a, &b| fit[b].total_cmp(&fit[a]).then(a.cmp(&b)));
    // Regions a move has touched this round: dropped, split, or beside a dropped one.
    let mut touched = vec![false; seeds.len()];
    let mut exchanged = seeds.to_vec();
    let mut drops = cheapest.into_iter();
    for split in worst_fitting {
        if touched[split] || component_seeds[slot(seeds[split])] < MIN_COMPONENT_SEEDS {
            continue;
        }
        let Some(dropped) = drops.by_ref().find(|&r| {
            r != split
                && !touched[r]
                && !neighbours[r].iter().any(|&n| touched[n as usize])
                && component_seeds[slot(seeds[r])] > MIN_COMPONENT_SEEDS
        }) else {
            break;
        };
        if drop_cost[dropped] >= SPLIT_SAVING * fit[split] {
            break;
        }
        exchanged[dropped] = worst[split].1;
        component_seeds[slot(seeds[dropped])] -= 1;
        component_seeds[slot(worst[split].1)] += 1;
        touched[split] = true;
        touched[dropped] = true;
        for &n in &neighbours[dropped] {
            touched[n as usize] = true;
        }
    }
    Ok(exchanged)
}

#[cfg(test)]
mod tests {
    use super::super::region_placement::settle;
    use super::*;
    use crate::region_quadric_vertices;
    use meshgnn_geometry::subdivided_cube;

    /// Σ_r Q_r(seed_r): how far the seeds' regions lie from their seeds' planes.
    fn total_fit(mesh: &TriMesh, seeds: &[u32]) -> f64 {
        let regions = SeedRegions::new(mesh, seeds).unwrap();
        let at = |v: u32| to_f64(mesh.vertices()[v as usize]);
        (0..seeds.len())
            .map(|r| regions.quadrics()[r].evaluate(at(seeds[r])))
            .sum()
    }

    /// `seeds` settled on their regions, then exchanged on the same regions, as a round of
    /// the neural simplifier does; the regions' settled seeds and the exchanged ones.
    fn settle_and_exchange(mesh: &TriMesh, seeds: &[u32]) -> (Vec<u32>, Vec<u32>) {
        let regions = SeedRegions::new(mesh, seeds).unwrap();
        let settled = region_quadric_vertices(mesh, &regions, seeds).unwrap();
        let exchanged = region_seed_exchange(mesh, &regions, &settled).unwrap();
        (settled, exchanged)
    }

    fn sorted(seeds: &[u32]) -> Vec<u32> {
        let mut s = seeds.to_vec();
        s.sort_unstable();
        s
    }

    #[test]
    fn seeds_leave_flat_faces_for_the_cubes_edges_and_the_fit_improves() {
        let cube = subdivided_cube(8);
        // Every seventh vertex, settled on its region's best vertex: regions across the
        // cube's edges and corners fit badly, those inside its faces exactly.
        let drawn: Vec<u32> = (0..cube.vertex_count() as u32).step_by(7).collect();
        let (settled, exchanged) = settle_and_exchange(&cube, &drawn);
        let after = settle(&cube, &exchanged).unwrap();
        assert_eq!(exchanged.len(), settled.len());
        let distinct = sorted(&exchanged);
        assert!(distinct.windows(2).all(|w| w[0] < w[1]));
        assert_ne!(exchanged, settled);
        let (before, now) = (total_fit(&cube, &settled), total_fit(&cube, &after));
        assert!(now < 0.8 * before, "fit {before} → {now}");
        // The same input, the same result.
        assert_eq!(settle_and_exchange(&cube, &drawn).1, exchanged);
    }

    #[test]
    fn a_component_with_few_seeds_neither_gives_nor_takes() {
        // Two cubes apart: the first with three seeds, the second with many.
        let small = subdivided_cube(4);
        let offset = small.vertex_count() as u32;
        let mut vertices = small.vertices().to_vec();
        vertices.extend(small.vertices().iter().map(|p| [p[0] + 5.0, p[1], p[2]]));
        let mut faces = small.triangles().to_vec();
        faces.extend(small.triangles().iter().map(|t| t.map(|v| v + offset)));
        let mesh = TriMesh::new(vertices, faces).unwrap();
        let few = [0, 40, 80];
        let many = (0..offset).step_by(5).map(|v| v + offset);
        let seeds: Vec<u32> = few.into_iter().chain(many).collect();
        let regions = SeedRegions::new(&mesh, &seeds).unwrap();
        let exchanged = region_seed_exchange(&mesh, &regions, &seeds).unwrap();
        assert_ne!(exchanged, seeds);
        let in_first: Vec<u32> = exchanged.iter().copied().filter(|&v| v < offset).collect();
        assert_eq!(sorted(&in_first), sorted(&few));
    }
}
