//! Lloyd relaxation of a point selection over the cloud it was taken from (a discrete
//! centroidal Voronoi tessellation, kept on the input points): each kept point moves to the
//! mean of the input points nearest to it, then to the input point nearest that mean.
//!
//! FPS leaves its points evenly spread but not centred in the regions they stand for; the
//! curvature metrics at one physical scale (SDM, CE, RE of thesis ch. 5.4) and the Chamfer
//! distance reward centred points (docs/pcsimplify_model.md, "Selector space"). Snapping back
//! keeps the result a selection — indices into the input — so it prefers points near local
//! means over FPS's outliers on noisy clouds.
//!
//! # Conventions
//! - Each step: every input point joins its nearest kept point (ties to the smaller kept
//!   position, as [`SpatialIndex`] orders them); a kept point with members moves to their mean
//!   (summed in input order, in `f64`), one without stays; then, in kept order, each takes the
//!   nearest input point to its mean that no earlier kept point took this step.
//! - The result has the length and order of `kept`, stays distinct and depends only on the
//!   inputs: deterministic, no seed. Cost per step: two k-NN passes, O(N log M + M log N).

use meshgnn_geometry::{SpatialIndex, squared_distance};
use rayon::prelude::*;

use crate::{Error, Result};

/// Input points a snapped mean looks through for one no earlier kept point took; beyond them
/// the nearest free point is searched over the whole cloud (rare: only where kept points are
/// denser than this in input points).
const SNAP_CANDIDATES: usize = 8;

/// `steps` Lloyd steps of the selection `kept` (distinct indices into `points: #N×3`), each
/// snapped back to the input points. Errors on an index out of range or repeated, or on
/// non-finite points.
///
/// ```
/// use meshgnn_graph::centroidal_relaxation;
/// // Ten points on a line; keeping the two ends, Lloyd moves them to the centres of the halves.
/// let points: Vec<[f32; 3]> = (0..10).map(|i| [i as f32, 0.0, 0.0]).collect();
/// assert_eq!(centroidal_relaxation(&points, &[0, 9], 1)?, vec![2, 7]);
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn centroidal_relaxation(points: &[[f32; 3]], kept: &[u32], steps: usize) -> Result<Vec<u32>> {
    centroidal_relaxation_indexed(points, None, kept, None, steps)
}

/// [`centroidal_relaxation`] with a [`SpatialIndex`] already built over `points` (one k-d tree
/// per cloud: the point simplifier's k-NN graph lends its own); `None` builds one. `owners:
/// #N`, when the caller knows it, is the position in `kept` of every input point's nearest kept
/// point (as [`crate::fast_farthest_point_sampling_with_owners`] gives it): the first step
/// then skips its k-NN pass. Errors as [`centroidal_relaxation`] does, on an index over
/// another number of points, and on owners of another length or out of range.
pub fn centroidal_relaxation_indexed(
    points: &[[f32; 3]],
    index: Option<&SpatialIndex>,
    kept: &[u32],
    owners: Option<&[u32]>,
    steps: usize,
) -> Result<Vec<u32>> {
    let n = points.len();
    if let Some(index) = index
        && index.len() != n
    {
        return Err(Error::InvalidParameter {
            name: "index",
            message: format!("covers {} points, the cloud has {n}", index.len()),
        });
    }
    let mut taken = vec![false; n];
    for &i in kept {
        let slot = taken
            .get_mut(i as usize)
            .ok_or_else(|| Error::InvalidParameter {
                name: "kept",
                message: format!("index {i} is outside the {n} points"),
            })?;
        if *slot {
            return Err(Error::InvalidParameter {
                name: "kept",
                message: format!("index {i} is kept twice"),
            });
        }
        *slot = true;
    }
    if let Some(owners) = owners {
        if owners.len() != n {
            return Err(Error::InvalidParameter {
                name: "owners",
                message: format!("{} owners for {n} points", owners.len()),
            });
        }
        if let Some(&o) = owners.iter().find(|&&o| o as usize >= kept.len()) {
            return Err(Error::InvalidParameter {
                name: "owners",
                message: format!("owner {o} is outside the {} kept points", kept.len()),
            });
        }
    }
    let mut current = kept.to_vec();
    if steps == 0 || kept.is_empty() {
        return Ok(current);
    }
    let built;
    let input = match index {
        Some(index) => index,
        None => {
            built = SpatialIndex::new(points)?;
            &built
        }
    };
    let mut owner: Vec<u32> = Vec::new();
    for step in 0..steps {
        let centres: Vec<[f32; 3]> = current.iter().map(|&i| points[i as usize]).collect();
        owner = match (step, owners) {
            (0, Some(owners)) => owners.to_vec(),
            (0, None) => SpatialIndex::new(&centres)?.knn(points, 1)?.indices,
            _ => nearest_centres(points, &centres, &owner)?,
        };
        let mut sums = vec![[0f64; 4]; current.len()];
        for (p, &o) in points.iter().zip(&owner) {
            let s = &mut sums[o as usize];
            for a in 0..3 {
                s[a] += f64::from(p[a]);
            }
            s[3] += 1.0;
        }
        let means: Vec<[f32; 3]> = sums
            .iter()
            .zip(&centres)
            .map(|(s, &c)| match s[3] > 0.0 {
                true => [0, 1, 2].map(|a| (s[a] / s[3]) as f32),
                false => c,
            })
            .collect();
        // the nearest input point of every mean; the few that an earlier kept point took this
        // step look further, one at a time
        let nearest = input.knn(&means, 1)?.indices;
        taken.fill(false);
        let mut candidates = Vec::with_capacity(SNAP_CANDIDATES);
        for (j, (mean, &first)) in means.iter().zip(&nearest).enumerate() {
            let pick = if taken[first as usize] {
                input.nearest(mean, SNAP_CANDIDATES.min(n), None, &mut candidates);
                match candidates.iter().find(|&&(_, i)| !taken[i as usize]) {
                    Some(&(_, i)) => i,
                    None => nearest_free(points, &taken, mean),
                }
            } else {
                first
            };
            taken[pick as usize] = true;
            current[j] = pick;
        }
    }
    Ok(current)
}

/// For each of `points`, the position of its nearest `centres` point (ties to the smaller
/// position, as [`SpatialIndex::knn`] with k = 1), searched within its distance to the centre
/// that owned it last step, `previous[i]`: the bound holds the answer and keeps the search
/// to the centres around each run of points.
fn nearest_centres(
    points: &[[f32; 3]],
    centres: &[[f32; 3]],
    previous: &[u32],
) -> Result<Vec<u32>> {
    let bounds: Vec<f32> = points
        .par_iter()
        .zip(previous)
        .map(|(p, &o)| squared_distance(p, &centres[o as usize]))
        .collect();
    let nearest = SpatialIndex::new(centres)?.nearest_within_each(points, &bounds)?;
    Ok(nearest
        .into_iter()
        .zip(previous)
        .map(|(c, &o)| c.unwrap_or(o))
        .collect())
}

/// The input point nearest `q` that is not taken (ties to the smaller index); some point is
/// free because fewer points are kept than there are.
fn nearest_free(points: &[[f32; 3]], taken: &[bool], q: &[f32; 3]) -> u32 {
    let mut best = (f32::INFINITY, 0u32);
    for (i, p) in points.iter().enumerate() {
        let d = meshgnn_geometry::squared_distance(p, q);
        if !taken[i] && d < best.0 {
            best = (d, i as u32);
        }
    }
    best.1
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{FpsStart, fast_farthest_point_sampling, fast_farthest_point_sampling_with_owners};
    use meshgnn_geometry::{icosphere, sample_surface};

    #[test]
    fn a_hand_computed_step_on_a_grid() {
        // 4×4 grid, keep the four corners: each quadrant's mean is (0.5, 0.5) from its corner,
        // snapped to the nearest grid point (ties: smaller index).
        let grid: Vec<[f32; 3]> = (0..16)
            .map(|i| [(i % 4) as f32, (i / 4) as f32, 0.0])
            .collect();
        let out = centroidal_relaxation(&grid, &[0, 3, 12, 15], 1).unwrap();
        assert_eq!(out, vec![0, 2, 8, 10]);
        // the means are exact; the second step leaves them
        assert_eq!(centroidal_relaxation(&grid, &out, 1).unwrap(), out);
    }

    #[test]
    fn distinct_deterministic_and_centred() {
        // random surface samples: FPS spreads them evenly but off-centre
        let sphere = sample_surface(&icosphere(3), 4000, 1).unwrap().points;
        let fps = fast_farthest_point_sampling(&sphere, 120, FpsStart::Seeded(2)).unwrap();
        let out = centroidal_relaxation(&sphere, &fps, 3).unwrap();
        assert_eq!(out, centroidal_relaxation(&sphere, &fps, 3).unwrap());
        let mut sorted = out.clone();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!(sorted.len(), 120);
        // the discrete CVT energy (mean squared distance to the nearest kept point) falls
        let energy = |kept: &[u32]| {
            let centres: Vec<[f32; 3]> = kept.iter().map(|&i| sphere[i as usize]).collect();
            let nn = SpatialIndex::new(&centres)
                .unwrap()
                .knn(&sphere, 1)
                .unwrap();
            nn.squared_distances
                .iter()
                .map(|&d| f64::from(d))
                .sum::<f64>()
        };
        assert!(
            energy(&out) < 0.97 * energy(&fps),
            "{} vs {}",
            energy(&out),
            energy(&fps)
        );
    }

    #[test]
    fn crowded_snaps_stay_distinct_and_bad_selections_are_refused() {
        // every point kept but one: all snaps compete for the same few points
        let line: Vec<[f32; 3]> = (0..12).map(|i| [i as f32, 0.0, 0.0]).collect();
        let kept: Vec<u32> = (0..11).collect();
        let mut out = centroidal_relaxation(&line, &kept, 2).unwrap();
        out.sort_unstable();
        out.dedup();
        assert_eq!(out.len(), 11);
        assert_eq!(
            centroidal_relaxation(&line, &[], 3).unwrap(),
            Vec::<u32>::new()
        );
        assert_eq!(
            centroidal_relaxation(&line, &[4, 1], 0).unwrap(),
            vec![4, 1]
        );
        assert!(centroidal_relaxation(&line, &[1, 1], 1).is_err());
        assert!(centroidal_relaxation(&line, &[12], 1).is_err());
        let other = SpatialIndex::new(&line[..5]).unwrap();
        assert!(centroidal_relaxation_indexed(&line, Some(&other), &[1], None, 1).is_err());
        let own = SpatialIndex::new(&line).unwrap();
        assert_eq!(
            centroidal_relaxation_indexed(&line, Some(&own), &[0, 11], None, 2).unwrap(),
            centroidal_relaxation(&line, &[0, 11], 2).unwrap()
        );
        assert!(centroidal_relaxation_indexed(&line, None, &[0, 11], Some(&[0; 5]), 1).is_err());
        assert!(centroidal_relaxation_indexed(&line, None, &[0, 11], Some(&[2; 12]), 1).is_err());
    }

    #[test]
    fn one_step_is_the_brute_force_rule_where_snaps_collide() {
        // points 200..300 repeat points 0..100, and both copies of 60 of them are kept: the
        // second copy's mean lands where the first one's snapped, so it looks past taken points
        let mut cloud = sample_surface(&icosphere(2), 300, 5).unwrap().points;
        for i in 0..100 {
            cloud[200 + i] = cloud[i];
        }
        let kept: Vec<u32> = (0..60).chain(200..260).chain([100, 150, 199]).collect();
        let centres: Vec<[f32; 3]> = kept.iter().map(|&i| cloud[i as usize]).collect();
        let by_distance_then_index =
            |q: &[f32; 3], among: &[[f32; 3]], skip: &dyn Fn(usize) -> bool| {
                (0..among.len())
                    .filter(|&j| !skip(j))
                    .min_by(|&a, &b| {
                        squared_distance(&among[a], q)
                            .total_cmp(&squared_distance(&among[b], q))
                            .then(a.cmp(&b))
                    })
                    .unwrap()
            };
        let mut sums = vec![[0f64; 4]; kept.len()];
        for p in &cloud {
            let s = &mut sums[by_distance_then_index(p, &centres, &|_| false)];
            for a in 0..3 {
                s[a] += f64::from(p[a]);
            }
            s[3] += 1.0;
        }
        let mut taken = vec![false; cloud.len()];
        let mut collisions = 0;
        let want: Vec<u32> = sums
            .iter()
            .zip(&centres)
            .map(|(s, c)| {
                let mean = match s[3] > 0.0 {
                    true => [0, 1, 2].map(|a| (s[a] / s[3]) as f32),
                    false => *c,
                };
                let free = by_distance_then_index(&mean, &cloud, &|i| taken[i]);
                collisions +=
                    usize::from(free != by_distance_then_index(&mean, &cloud, &|_| false));
                taken[free] = true;
                free as u32
            })
            .collect();
        assert!(
            collisions > 5,
            "{collisions} snaps looked past a taken point"
        );
        assert_eq!(centroidal_relaxation(&cloud, &kept, 1).unwrap(), want);
    }

    #[test]
    fn fps_owners_are_the_first_assignment() {
        // uniform, clustered and duplicated clouds: FPS's owners are the k-NN assignment, so
        // relaxing from them gives the same selection as relaxing from scratch
        let sphere = sample_surface(&icosphere(3), 3000, 7).unwrap().points;
        let clustered: Vec<[f32; 3]> = sphere
            .iter()
            .enumerate()
            .map(|(i, p)| match i % 3 {
                0 => [p[0] * 0.01, p[1] * 0.01, p[2] * 0.01],
                _ => *p,
            })
            .collect();
        let duplicated: Vec<[f32; 3]> = sphere[..500].iter().cycle().take(1500).copied().collect();
        for (cloud, k) in [(&sphere, 150), (&clustered, 150), (&duplicated, 700)] {
            let (kept, owners) =
                fast_farthest_point_sampling_with_owners(cloud, k, FpsStart::Seeded(2)).unwrap();
            assert_eq!(
                kept,
                fast_farthest_point_sampling(cloud, k, FpsStart::Seeded(2)).unwrap()
            );
            let centres: Vec<[f32; 3]> = kept.iter().map(|&i| cloud[i as usize]).collect();
            let nearest = SpatialIndex::new(&centres).unwrap().knn(cloud, 1).unwrap();
            assert_eq!(owners, nearest.indices);
            assert_eq!(
                centroidal_relaxation_indexed(cloud, None, &kept, Some(&owners), 3).unwrap(),
                centroidal_relaxation(cloud, &kept, 3).unwrap()
            );
            // the later steps' bounded search is the plain nearest-centre assignment, from any
            // previous owner (here: every point's owner shifted to another centre)
            let shifted: Vec<u32> = owners.iter().map(|&o| (o + 1) % k as u32).collect();
            assert_eq!(
                nearest_centres(cloud, &centres, &shifted).unwrap(),
                nearest.indices
            );
        }
    }
}
