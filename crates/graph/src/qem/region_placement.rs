//! Vertex placement for a simplifier that selects input vertices (the neural mesh simplifier
//! of thesis ch. 6): every selected vertex stands for its geodesic Voronoi region of the input
//! and moves to the point that minimises the quadric error of the input faces around that
//! region — Garland & Heckbert's quadrics summed per cluster, as clustering simplifiers place
//! their representatives (Lindstrom, "Out-of-core simplification of large polygonal models",
//! SIGGRAPH 2000; Valette et al.'s ACVD). A selection cannot put a vertex where the surface is
//! best approximated (off the input's vertices, outside a convex bend, on a crease line
//! between samples); this step can, while the faces stay as chosen. Its discrete form,
//! [`region_quadric_vertices`], moves each selected vertex to the input vertex of its region
//! that fits the region's faces best, before the faces are chosen.
//!
//! # Conventions
//! - The solve is regularised towards the selected position ([`Quadric::regularized_point`]):
//!   a flat region moves only along its normal, a crease only across its line.
//! - Open borders add the decimation's border planes (through each border edge, perpendicular
//!   to its face, weight `boundary_weight · |e|²`), so a border stays where it was.
//! - A vertex stays selected where its optimum lies farther from it than the farthest input
//!   vertex of its region, and where moving it would turn one of its output faces by more
//!   than acos(0.2) ≈ 78° (the decimation's flip bound); vertices after the selected ones
//!   (hole-filling centres) never move.

use meshgnn_geometry::vec3::{cross, dot, norm, sub, to_f64};
use meshgnn_geometry::{TriMesh, edge_topology};

use super::decimation::DecimationOptions;
use super::quadric::Quadric;
use super::seed_regions::{SeedRegions, add_to_region, face_plane};
use crate::error::{Error, Result};

/// Pull of the selected position on its region's optimum, relative to the region's mean
/// plane weight: strong enough to fix the directions no plane constrains, weak enough
/// (1/1000) to leave the others to the quadric.
const ANCHOR_STRENGTH: f64 = 1e-3;

/// A moved face must keep its normal within acos(0.2) of its normal before the move.
const MIN_NORMAL_COSINE: f64 = 0.2;

/// The positions of `output`'s vertices after moving each selected vertex `o < seeds.len()`
/// (which sits at input vertex `seeds[o]`) to the quadric optimum of its region in `regions`
/// (module docs; [`SeedRegions::new`] of `input` and these seeds, which a caller may build
/// while it chooses the faces); the other vertices keep theirs. Errors when `seeds` is longer
/// than `output`'s vertex list, does not match the regions, or names a vertex of `input` out
/// of range or twice.
///
/// ```
/// use meshgnn_geometry::{TriMesh, icosphere};
/// use meshgnn_graph::{SeedRegions, region_quadric_placement};
/// // A coarse selection of a sphere's vertices sits on the sphere; its triangles cut inside.
/// // Placed, the vertices move outwards so the triangles straddle the surface.
/// let sphere = icosphere(4);
/// let coarse = icosphere(1);
/// let seeds: Vec<u32> = (0..coarse.vertex_count() as u32).collect();
/// let regions = SeedRegions::new(&sphere, &seeds)?;
/// let placed = region_quadric_placement(&sphere, regions, &seeds, &coarse)?;
/// let radius = |p: [f32; 3]| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
/// assert!(placed.iter().all(|&p| radius(p) > 1.0 && radius(p) < 1.1));
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn region_quadric_placement(
    input: &TriMesh,
    regions: SeedRegions,
    seeds: &[u32],
    output: &TriMesh,
) -> Result<Vec<[f32; 3]>> {
    let selected = output.vertices();
    if seeds.len() > selected.len() {
        return Err(Error::InvalidParameter {
            name: "seeds",
            message: format!(
                "{} seeds for an output of {} vertices",
                seeds.len(),
                selected.len()
            ),
        });
    }
    regions.seed_of_vertex(input, seeds)?;
    let SeedRegions {
        region,
        mut quadrics,
    } = regions;
    // The selected positions; the first `seeds.len()` are the anchors of the solves.
    let anchors: Vec<[f64; 3]> = selected.iter().map(|&p| to_f64(p)).collect();
    add_border_quadrics(input, &region, &mut quadrics);
    let mut reach = vec![0.0f64; seeds.len()];
    for (p, &r) in input.vertices().iter().zip(&region) {
        if let Some(reach) = reach.get_mut(r as usize) {
            *reach = reach.max(norm(sub(to_f64(*p), anchors[r as usize])));
        }
    }
    let mut placed = anchors.clone();
    for (o, (quadric, anchor)) in quadrics.iter().zip(&anchors).enumerate() {
        if let Some(p) = quadric.regularized_point(*anchor, ANCHOR_STRENGTH)
            && norm(sub(p, *anchor)) <= reach[o]
        {
            placed[o] = p;
        }
    }
    undo_flipping_moves(output, &anchors, &mut placed);
    Ok(placed.iter().map(|p| p.map(|x| x as f32)).collect())
}

/// `seeds` moved within their regions: each to the vertex of its region (in `regions`, built
/// from these seeds or from seeds each inside the region it names) with the least error under
/// the region's face quadric, `Q(v) + μ·|v − seed|²` (`μ` the pull of
/// [`region_quadric_placement`]'s solve, so that where every vertex fits, as on a flat
/// region, the seed stays): the discrete form of that placement, for a simplifier to take
/// before it connects its selection, so that a seed whose region holds a corner moves onto
/// it, one whose region holds a crease onto the crease, and one on a curved region towards
/// its middle. Border planes are left out: they would pull every region that touches an open
/// border onto it. Errors when the seeds do not match the regions, are out of range or
/// repeated.
///
/// ```
/// use meshgnn_geometry::grid_plane;
/// use meshgnn_graph::{SeedRegions, region_quadric_vertices};
/// // A flat square: every vertex fits its region's plane, each seed stays.
/// let square = grid_plane(4, 4);
/// let seeds = [0, 12, 24];
/// let regions = SeedRegions::new(&square, &seeds)?;
/// assert_eq!(region_quadric_vertices(&square, &regions, &seeds)?, seeds);
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn region_quadric_vertices(
    input: &TriMesh,
    regions: &SeedRegions,
    seeds: &[u32],
) -> Result<Vec<u32>> {
    // Another seed's vertex is never taken: a seed at the position of another (coincident
    // vertices joined by a zero-length edge) may lie in that one's region and then keeps its
    // place, so the result stays distinct. A seed in its own region is the first candidate,
    // so a tie (a region without area) keeps it.
    let seed_of = regions.seed_of_vertex(input, seeds)?;
    let (region, quadrics) = (regions.region(), regions.quadrics());
    let error = |r: usize, v: u32| {
        let quadric = &quadrics[r];
        let p = to_f64(input.vertices()[v as usize]);
        let d = sub(p, to_f64(input.vertices()[seeds[r] as usize]));
        quadric.evaluate(p) + ANCHOR_STRENGTH * quadric.weight() / 3.0 * dot(d, d)
    };
    let mut best: Vec<(f64, u32)> = seeds
        .iter()
        .enumerate()
        .map(|(i, &s)| {
            if region[s as usize] as usize == i {
                (error(i, s), s)
            } else {
                (f64::INFINITY, s)
            }
        })
        .collect();
    for (v, &r) in region.iter().enumerate() {
        let Some(&(least, _)) = best.get(r as usize) else {
            continue; // reached by no seed
        };
        if seed_of[v] != u32::MAX {
            continue; // a seed: its own region's first candidate, or another's to leave alone
        }
        let e = error(r as usize, v as u32);
        if e < least {
            best[r as usize] = (e, v as u32);
        }
    }
    Ok(best.into_iter().map(|(_, v)| v).collect())
}

/// `seeds` settled on the regions they make (the tests' shorthand for a settling round).
#[cfg(test)]
pub(super) fn settle(input: &TriMesh, seeds: &[u32]) -> Result<Vec<u32>> {
    region_quadric_vertices(input, &SeedRegions::new(input, seeds)?, seeds)
}

/// Adds to each region the border planes of the border edges it touches (module docs).
fn add_border_quadrics(input: &TriMesh, region: &[u32], quadrics: &mut [Quadric]) {
    let boundary_weight = DecimationOptions::default().boundary_weight;
    let topology = edge_topology(input);
    for (e, &[a, b]) in topology.edges().iter().enumerate() {
        if let [incidence] = topology.incidences(e) {
            let (normal, _) = face_plane(input, &input.triangles()[incidence.face as usize]);
            let at = |v: u32| to_f64(input.vertices()[v as usize]);
            let plane = Quadric::border_plane(at(a), at(b), normal, boundary_weight);
            add_to_region(quadrics, region, a, plane);
            add_to_region(quadrics, region, b, plane);
        }
    }
}

/// Puts moved vertices back at their anchors until no face of `output` turns by more than
/// acos([`MIN_NORMAL_COSINE`]) from its normal at the anchors (faces degenerate there are not
/// judged). Terminates: each round puts back at least one vertex or stops.
fn undo_flipping_moves(output: &TriMesh, anchors: &[[f64; 3]], placed: &mut [[f64; 3]]) {
    let normal = |positions: &[[f64; 3]], t: &[u32; 3]| {
        let [p0, p1, p2] = t.map(|v| positions[v as usize]);
        cross(sub(p1, p0), sub(p2, p0))
    };
    let before: Vec<[f64; 3]> = output
        .triangles()
        .iter()
        .map(|t| normal(anchors, t))
        .collect();
    loop {
        let mut put_back: Vec<u32> = Vec::new();
        for (t, n0) in output.triangles().iter().zip(&before) {
            let n1 = normal(placed, t);
            let turned = dot(*n0, n1) <= MIN_NORMAL_COSINE * norm(*n0) * norm(n1);
            if norm(*n0) > 0.0 && turned {
                put_back.extend(
                    t.iter()
                        .filter(|&&v| placed[v as usize] != anchors[v as usize]),
                );
            }
        }
        if put_back.is_empty() {
            return;
        }
        for v in put_back {
            placed[v as usize] = anchors[v as usize];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshgnn_geometry::{geodesic_voronoi_regions, grid_plane, icosphere};

    fn radius(p: [f32; 3]) -> f64 {
        norm(to_f64(p))
    }

    fn regions(input: &TriMesh, seeds: &[u32]) -> SeedRegions {
        SeedRegions::new(input, seeds).unwrap()
    }

    /// Mean |radius − 1| over the points of each face at barycentric steps of 1/8.
    fn mean_radial_error(vertices: &[[f32; 3]], mesh: &TriMesh) -> f64 {
        let (mut sum, mut count) = (0.0, 0.0);
        for t in mesh.triangles() {
            let [a, b, c] = t.map(|v| to_f64(vertices[v as usize]));
            for i in 0..=8 {
                for j in 0..=8 - i {
                    let (u, v) = (f64::from(i) / 8.0, f64::from(j) / 8.0);
                    let p: [f64; 3] =
                        std::array::from_fn(|k| a[k] + u * (b[k] - a[k]) + v * (c[k] - a[k]));
                    sum += (norm(p) - 1.0).abs();
                    count += 1.0;
                }
            }
        }
        sum / count
    }

    #[test]
    fn a_seed_beside_a_corner_moves_onto_it() {
        // The cube [-1, 1]³ in cells of 1/3, one seed per octant on the face x = ±1, two
        // cells in from the corner along y and z: its region holds the corner, the one vertex
        // on all three of the region's planes.
        let cube = meshgnn_geometry::subdivided_cube(6);
        let index_of = |p: [f32; 3]| {
            let near = |a: [f32; 3]| (0..3).all(|k| (a[k] - p[k]).abs() < 1e-6);
            cube.vertices().iter().position(|&q| near(q)).unwrap() as u32
        };
        let octants: Vec<[f32; 3]> = (0..8)
            .map(|i| [0, 1, 2].map(|k| if i >> k & 1 == 1 { 1.0 } else { -1.0 }))
            .collect();
        let two_thirds = 2.0 / 3.0;
        let seeds: Vec<u32> = octants
            .iter()
            .map(|c| index_of([c[0], c[1] * two_thirds, c[2] * two_thirds]))
            .collect();
        let corners: Vec<u32> = octants.iter().map(|&c| index_of(c)).collect();
        assert_eq!(settle(&cube, &seeds).unwrap(), corners);
    }

    #[test]
    fn a_seed_beside_a_crease_moves_onto_it_and_the_others_stay() {
        // Seeds on the cube [-1, 1]³ in cells of 1/3 at every vertex whose coordinates are
        // ±1 or ±1/3 (corners, crease points, face points), one of them, the crease point
        // (1, 1, 1/3), put a cell away from its crease, onto the face x = 1. Its region holds
        // that crease point and no corner; every other seed already fits its region best.
        let cube = meshgnn_geometry::subdivided_cube(6);
        let on_lattice = |x: f32| {
            [-1.0, -1.0 / 3.0, 1.0 / 3.0, 1.0]
                .iter()
                .any(|l| (x - l).abs() < 1e-6)
        };
        let mut seeds: Vec<u32> = (0..cube.vertex_count() as u32)
            .filter(|&v| cube.vertices()[v as usize].iter().all(|&x| on_lattice(x)))
            .collect();
        let index_of = |p: [f32; 3]| {
            let near = |a: [f32; 3]| (0..3).all(|k| (a[k] - p[k]).abs() < 1e-6);
            cube.vertices().iter().position(|&q| near(q)).unwrap() as u32
        };
        let crease = index_of([1.0, 1.0, 1.0 / 3.0]);
        let beside = index_of([1.0, 2.0 / 3.0, 1.0 / 3.0]);
        let moved_seed = seeds.iter().position(|&s| s == crease).unwrap();
        seeds[moved_seed] = beside;
        let mut expected = seeds.clone();
        expected[moved_seed] = crease;
        assert_eq!(settle(&cube, &seeds).unwrap(), expected);
    }

    #[test]
    fn seeds_at_one_position_stay_distinct() {
        // Vertex 9 sits on the centre vertex 4 of a 3 × 3 grid, joined to it by a zero-length
        // edge (a degenerate face): both seeds are at distance 0 from both vertices.
        let grid = grid_plane(2, 2);
        let mut vertices = grid.vertices().to_vec();
        vertices.push(vertices[4]);
        let mut faces = grid.triangles().to_vec();
        faces.push([4, 9, 0]);
        let mesh = TriMesh::new(vertices, faces).unwrap();
        for seeds in [[4, 9], [9, 4]] {
            let moved = settle(&mesh, &seeds).unwrap();
            assert_ne!(moved[0], moved[1], "{seeds:?} → {moved:?}");
        }
    }

    #[test]
    fn a_region_without_area_keeps_its_seed() {
        // A 3 × 3 grid squashed onto a line: every face degenerate, every error zero.
        let grid = grid_plane(2, 2);
        let line: Vec<[f32; 3]> = grid.vertices().iter().map(|p| [p[0], 0.0, 0.0]).collect();
        let mesh = TriMesh::new(line, grid.triangles().to_vec()).unwrap();
        assert_eq!(settle(&mesh, &[4]).unwrap(), vec![4]);
    }

    #[test]
    fn a_coarse_sphere_moves_outwards_and_fits_the_surface_better() {
        // Selected on the unit sphere, the coarse triangles lie inside it; each region's
        // optimum is just outside, so the faces straddle the surface.
        let fine = icosphere(5);
        let coarse = icosphere(2);
        let seeds: Vec<u32> = (0..coarse.vertex_count() as u32).collect();
        let placed =
            region_quadric_placement(&fine, regions(&fine, &seeds), &seeds, &coarse).unwrap();
        for &p in &placed {
            assert!(radius(p) > 1.0 && radius(p) < 1.02, "radius {}", radius(p));
        }
        let before = mean_radial_error(coarse.vertices(), &coarse);
        let after = mean_radial_error(&placed, &coarse);
        assert!(after < 0.6 * before, "{after} against {before}");
    }

    #[test]
    fn a_flat_grid_stays_flat_and_its_border_regions_move_onto_the_border() {
        // A plane fixes only its normal: interior regions stay where they are; a region
        // touching the border is held on the border's line by the border planes (and in its
        // corner where two lines meet), as the output vertex it gives is a border vertex.
        let fine = grid_plane(16, 16);
        let seeds: Vec<u32> = (0..fine.vertex_count() as u32).step_by(5).collect();
        let positions: Vec<[f32; 3]> = seeds.iter().map(|&s| fine.vertices()[s as usize]).collect();
        let output = TriMesh::new(positions.clone(), vec![]).unwrap();
        let placed =
            region_quadric_placement(&fine, regions(&fine, &seeds), &seeds, &output).unwrap();
        let region = geodesic_voronoi_regions(&fine, &seeds).unwrap();
        // Within 1e-4 (the pull of the anchor; the grid step is 1/16).
        let on_border = |p: [f32; 3]| {
            p[..2]
                .iter()
                .any(|&x| x.abs() < 1e-4 || (x - 1.0).abs() < 1e-4)
        };
        let mut moved = 0;
        for (o, (p, q)) in placed.iter().zip(&positions).enumerate() {
            assert!(p[2].abs() < 1e-6, "{p:?} left the plane");
            let touches_border = fine
                .vertices()
                .iter()
                .zip(&region)
                .any(|(&v, &r)| r as usize == o && on_border(v));
            if touches_border {
                assert!(on_border(*p), "{p:?} (from {q:?}) is off the border");
                moved += usize::from(p != q);
            } else {
                assert!(
                    norm(sub(to_f64(*p), to_f64(*q))) < 1e-6,
                    "{p:?} moved from {q:?}"
                );
            }
        }
        assert!(moved > 0);
    }

    #[test]
    fn seeds_next_to_a_cubes_corners_snap_to_the_corners() {
        // One seed a step from each corner: each region holds its corner and parts of the
        // three faces meeting there, whose planes' optimum is the corner itself.
        let cube = meshgnn_geometry::subdivided_cube(8);
        let v = cube.vertices();
        let extent = v.iter().map(|p| p[0]).fold(0.0f32, f32::max);
        let corners: Vec<u32> = (0..v.len() as u32)
            .filter(|&i| v[i as usize].iter().all(|x| x.abs() == extent))
            .collect();
        assert_eq!(corners.len(), 8);
        let seeds: Vec<u32> = corners
            .iter()
            .map(|&c| {
                let neighbours = cube.triangles().iter().filter(|t| t.contains(&c)).flatten();
                *neighbours.filter(|&&u| u != c).min().unwrap()
            })
            .collect();
        let output = TriMesh::new(seeds.iter().map(|&s| v[s as usize]).collect(), vec![]).unwrap();
        let placed =
            region_quadric_placement(&cube, regions(&cube, &seeds), &seeds, &output).unwrap();
        let step = f64::from(extent) / 4.0;
        for (p, &c) in placed.iter().zip(&corners) {
            let miss = norm(sub(to_f64(*p), to_f64(v[c as usize])));
            assert!(miss < 0.01 * step, "{miss} from the corner");
        }
    }

    #[test]
    fn a_move_that_would_flip_a_face_is_undone() {
        // A square of two faces whose fourth vertex is pulled across the diagonal.
        let anchors = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        let output = TriMesh::new(
            anchors
                .iter()
                .map(|p: &[f64; 3]| p.map(|x| x as f32))
                .collect(),
            vec![[0, 1, 2], [0, 2, 3]],
        )
        .unwrap();
        let mut placed = anchors;
        placed[3] = [0.9, 0.2, 0.0];
        placed[1] = [1.1, 0.0, 0.01];
        undo_flipping_moves(&output, &anchors, &mut placed);
        assert_eq!(placed[3], anchors[3]);
        assert_eq!(placed[1], [1.1, 0.0, 0.01]);
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(24))]
        /// On a noisy sphere (some faces cut away, so it has borders) with any seeds and
        /// their Voronoi-dual faces: finite positions, no face turned past the bound, every
        /// vertex within its region's reach, the same result twice; and the seeds moved to
        /// their regions' best-fitting vertices stay distinct and in their regions.
        #[test]
        fn placement_is_finite_bounded_and_never_flips_a_face(
            noise in 0.0f32..0.3,
            stride in 2usize..9,
            holes in 0usize..40,
            salt in 0u32..1000,
        ) {
            let sphere = icosphere(3);
            let jitter = |i: usize, k: usize| {
                let h = (i as u32 * 3 + k as u32).wrapping_mul(2_654_435_761) ^ salt;
                (h % 1000) as f32 / 1000.0 - 0.5
            };
            let vertices: Vec<[f32; 3]> = sphere
                .vertices()
                .iter()
                .enumerate()
                .map(|(i, p)| std::array::from_fn(|k| p[k] * (1.0 + noise * jitter(i, k))))
                .collect();
            let faces: Vec<[u32; 3]> = sphere
                .triangles()
                .iter()
                .enumerate()
                .filter(|&(f, _)| holes == 0 || f % (holes + 7) != 0)
                .map(|(_, t)| *t)
                .collect();
            let input = TriMesh::new(vertices, faces).unwrap();
            let seeds: Vec<u32> = (salt as usize % stride..input.vertex_count())
                .step_by(stride)
                .map(|v| v as u32)
                .collect();
            let dual = meshgnn_geometry::voronoi_dual_triangles(&input, &seeds).unwrap();
            let corners = seeds.iter().map(|&s| input.vertices()[s as usize]).collect();
            let output = TriMesh::new(corners, dual).unwrap();
            let placed = region_quadric_placement(&input, regions(&input, &seeds), &seeds, &output).unwrap();
            proptest::prop_assert_eq!(&placed, &region_quadric_placement(&input, regions(&input, &seeds), &seeds, &output).unwrap());
            let region = geodesic_voronoi_regions(&input, &seeds).unwrap();
            let anchor = |o: usize| to_f64(output.vertices()[o]);
            for (o, p) in placed.iter().enumerate() {
                proptest::prop_assert!(p.iter().all(|x| x.is_finite()));
                let reach = input
                    .vertices()
                    .iter()
                    .zip(&region)
                    .filter(|&(_, &r)| r as usize == o)
                    .map(|(&v, _)| norm(sub(to_f64(v), anchor(o))))
                    .fold(0.0, f64::max);
                proptest::prop_assert!(norm(sub(to_f64(*p), anchor(o))) <= reach * (1.0 + 1e-5) + 1e-6);
            }
            for t in output.triangles() {
                let [a, b, c] = t.map(|v| anchor(v as usize));
                let n0 = cross(sub(b, a), sub(c, a));
                let [a, b, c] = t.map(|v| to_f64(placed[v as usize]));
                let n1 = cross(sub(b, a), sub(c, a));
                if norm(n0) > 0.0 {
                    // The bound, with room for the rounding to f32.
                    proptest::prop_assert!(dot(n0, n1) > (MIN_NORMAL_COSINE - 1e-3) * norm(n0) * norm(n1));
                }
            }
            // The discrete form on the same input: one distinct vertex per seed, each in its
            // seed's region, the same result twice.
            let moved = settle(&input, &seeds).unwrap();
            let mut distinct = moved.clone();
            distinct.sort_unstable();
            distinct.dedup();
            proptest::prop_assert_eq!(distinct.len(), seeds.len());
            for (o, &m) in moved.iter().enumerate() {
                proptest::prop_assert_eq!(region[m as usize] as usize, o);
            }
            proptest::prop_assert_eq!(&moved, &settle(&input, &seeds).unwrap());
        }
    }

    #[test]
    fn too_many_or_repeated_seeds_are_errors() {
        let sphere = icosphere(1);
        let output = TriMesh::new(sphere.vertices()[..2].to_vec(), vec![]).unwrap();
        let three = [0, 1, 2];
        assert!(
            region_quadric_placement(&sphere, regions(&sphere, &three), &three, &output).is_err()
        );
        assert!(SeedRegions::new(&sphere, &[0, 0]).is_err());
        // Seeds that are not the regions': too few, or one repeated.
        assert!(
            region_quadric_placement(&sphere, regions(&sphere, &[0, 1]), &[0], &output).is_err()
        );
        assert!(
            region_quadric_placement(&sphere, regions(&sphere, &[0, 1]), &[0, 0], &output).is_err()
        );
        assert!(
            region_quadric_placement(&sphere, regions(&sphere, &[0, 1]), &[0, 1], &output).is_ok()
        );
    }
}
