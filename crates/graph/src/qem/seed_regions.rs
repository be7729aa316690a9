//! The geodesic Voronoi regions of a vertex selection with each region's summed face quadric:
//! what the moves of the neural mesh simplifier's seeds judge by ([`super::region_quadric_vertices`]
//! settles each seed on its region's best-fitting vertex, [`super::region_seed_exchange`]
//! moves seeds between regions). The partition is the one walk over the whole input of a
//! move; a round's two moves share one: the seeds the first move settles stay inside the
//! regions they settled in, so the second judges them on those regions.

use meshgnn_geometry::vec3::{cross, norm, sub, to_f64};
use meshgnn_geometry::{TriMesh, geodesic_voronoi_regions};

use super::quadric::Quadric;
use crate::error::{Error, Result};

/// Each input vertex's region among a selection and every region's face quadric.
#[derive(Clone, Debug)]
pub struct SeedRegions {
    pub(super) region: Vec<u32>,
    pub(super) quadrics: Vec<Quadric>,
}

impl SeedRegions {
    /// The geodesic Voronoi regions of `seeds` (each vertex to its nearest seed along the
    /// input's edges, [`geodesic_voronoi_regions`]) and per region the area-weighted plane
    /// quadrics of every face at each of its corners in the region. Errors when a seed is out
    /// of range or repeated.
    ///
    /// ```
    /// use meshgnn_geometry::grid_plane;
    /// use meshgnn_graph::SeedRegions;
    /// // Two seeds at opposite corners of a flat square: each region's quadric is the
    /// // square's plane, which fits every vertex exactly.
    /// let square = grid_plane(4, 4);
    /// let regions = SeedRegions::new(&square, &[0, 24])?;
    /// assert_eq!(regions.len(), 2);
    /// assert_eq!(regions.region()[0], 0);
    /// assert_eq!(regions.region()[24], 1);
    /// assert!(regions.quadrics()[1].evaluate([0.5, 0.5, 0.0]).abs() < 1e-12);
    /// # Ok::<(), meshgnn_graph::Error>(())
    /// ```
    pub fn new(input: &TriMesh, seeds: &[u32]) -> Result<Self> {
        let region = geodesic_voronoi_regions(input, seeds)?;
        let quadrics = region_face_quadrics(input, &region, seeds.len());
        Ok(Self { region, quadrics })
    }

    /// The number of regions (the seeds it was built from).
    pub fn len(&self) -> usize {
        self.quadrics.len()
    }

    /// Whether it was built from no seeds.
    pub fn is_empty(&self) -> bool {
        self.quadrics.is_empty()
    }

    /// Each input vertex's region (index into the seeds), `u32::MAX` where no seed reaches.
    pub fn region(&self) -> &[u32] {
        &self.region
    }

    /// Each region's summed face quadric.
    pub fn quadrics(&self) -> &[Quadric] {
        &self.quadrics
    }

    /// Checks that `seeds` (one per region, as a move takes them) are distinct vertices of
    /// `input`, the mesh the regions were built on; returns, per input vertex, the index of
    /// the seed on it or `u32::MAX`.
    pub(super) fn seed_of_vertex(&self, input: &TriMesh, seeds: &[u32]) -> Result<Vec<u32>> {
        if self.region.len() != input.vertex_count() || seeds.len() != self.len() {
            return Err(Error::InvalidParameter {
                name: "seeds",
                message: format!(
                    "{} seeds on {} vertices for {} regions of {} vertices",
                    seeds.len(),
                    input.vertex_count(),
                    self.len(),
                    self.region.len()
                ),
            });
        }
        Ok(meshgnn_geometry::seed_of_vertex(
            input.vertex_count(),
            seeds,
        )?)
    }
}

/// The area-weighted normal (doubled) of face `t` and one of its corners.
pub(super) fn face_plane(input: &TriMesh, t: &[u32; 3]) -> ([f64; 3], [f64; 3]) {
    let [p0, p1, p2] = t.map(|v| to_f64(input.vertices()[v as usize]));
    (cross(sub(p1, p0), sub(p2, p0)), p0)
}

/// Adds `quadric` to the region of input vertex `v`, if a seed reached it.
pub(super) fn add_to_region(quadrics: &mut [Quadric], region: &[u32], v: u32, quadric: Quadric) {
    if let Some(sum) = quadrics.get_mut(region[v as usize] as usize) {
        *sum += quadric;
    }
}

/// Per region, the area-weighted plane quadrics of every face at each of its corners in the
/// region.
fn region_face_quadrics(input: &TriMesh, region: &[u32], regions: usize) -> Vec<Quadric> {
    let mut quadrics = vec![Quadric::default(); regions];
    for t in input.triangles() {
        let (normal, point) = face_plane(input, t);
        let plane = Quadric::from_plane(normal, point, 0.5 * norm(normal));
        for &v in t {
            add_to_region(&mut quadrics, region, v, plane);
        }
    }
    quadrics
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshgnn_geometry::grid_plane;

    #[test]
    fn seeds_must_match_the_regions_and_be_distinct_vertices() {
        let square = grid_plane(4, 4);
        let regions = SeedRegions::new(&square, &[0, 24]).unwrap();
        let seed_of = regions.seed_of_vertex(&square, &[6, 24]).unwrap();
        assert_eq!((seed_of[6], seed_of[24], seed_of[0]), (0, 1, u32::MAX));
        for seeds in [&[0][..], &[0, 24, 12], &[0, 25], &[24, 24]] {
            assert!(regions.seed_of_vertex(&square, seeds).is_err(), "{seeds:?}");
        }
        let other = grid_plane(3, 3);
        assert!(regions.seed_of_vertex(&other, &[0, 1]).is_err());
    }
}
