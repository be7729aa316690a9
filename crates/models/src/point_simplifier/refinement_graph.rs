//! The k-NN graph between the selected cluster centres and the input points that AttRef
//! (thesis eq. 5.5, k = 15) refines over, with the neighbour offsets it consumes.
//!
//! # Conventions
//! - Row `i` lists the `k` input points nearest to centre `i` (the centre itself first, at
//!   offset 0), `neighbours: (M·k)` `u32`.
//! - Offsets are expressed in units of the centre's neighbourhood radius
//!   `s_i = (1/k Σ_j ‖p_j − p_{c_i}‖²)^{1/2}`: `offsets = (p_j − p_{c_i}) / s_i`, `(M·k, 3)`,
//!   and AttRef multiplies its output by `s_i` (`scales: (M, 1)`). Beyond the thesis: this makes
//!   the layer invariant to the sampling density, so weights trained on clouds of a few
//!   thousand points apply unchanged to millions. A centre whose neighbours all coincide with
//!   it gets `s_i = 0` (no displacement).
//! - Everything here is a constant of the autograd graph: positions are inputs, not outputs
//!   of learnable layers.

use candle_core::{Device, Tensor};
use meshgnn_geometry::SpatialIndex;
use rayon::prelude::*;

use crate::{Error, Result};

/// Centres, their neighbours in the input cloud and normalised offsets (see module docs).
#[derive(Clone, Debug)]
pub struct RefinementGraph {
    /// Selected centre indices into the input, `(M)` `u32`.
    pub centres: Tensor,
    /// Neighbour indices into the input, `(M·k)` `u32`, nearest first.
    pub neighbours: Tensor,
    /// `(p_j − p_c) / s_c`, `(M·k, 3)`.
    pub offsets: Tensor,
    /// Neighbourhood radius `s_c`, `(M, 1)`.
    pub scales: Tensor,
    /// Centre positions `p_c`, `(M, 3)`.
    pub positions: Tensor,
    /// Neighbours per centre k.
    pub k: usize,
}

impl RefinementGraph {
    /// The input points the graph reads (centres and their neighbours), sorted and distinct:
    /// the only points whose embeddings AttRef needs.
    pub fn support(&self) -> Result<Vec<u32>> {
        let mut support: Vec<u32> = self.neighbours.to_vec1()?;
        support.extend(self.centres.to_vec1::<u32>()?);
        support.par_sort_unstable();
        support.dedup();
        Ok(support)
    }

    /// The same graph with its point indices replaced by their positions in `support` (sorted
    /// and distinct, holding every point the graph reads, as [`RefinementGraph::support`]):
    /// AttRef then reads embeddings computed for the support alone. Errors on a point
    /// missing from `support`.
    pub fn renumbered(&self, support: &[u32]) -> Result<Self> {
        let renumber = |t: &Tensor| -> Result<Tensor> {
            let ids: Vec<u32> = t.to_vec1()?;
            let positions = ids
                .par_iter()
                .map(|&i| {
                    support
                        .binary_search(&i)
                        .map(|p| p as u32)
                        .map_err(|_| Error::Invalid {
                            what: format!("point {i}"),
                            reason: "is missing from the support".into(),
                        })
                })
                .collect::<Result<Vec<u32>>>()?;
            Ok(Tensor::from_vec(positions, ids.len(), t.device())?)
        };
        Ok(Self {
            centres: renumber(&self.centres)?,
            neighbours: renumber(&self.neighbours)?,
            ..self.clone()
        })
    }
}

/// Builds the AttRef graph of `centres: #M` (indices into `points: #N×3`) with `k` neighbours
/// each (15 in the thesis; capped at N). O((N + M k) log N), parallel over centres.
///
/// ```
/// use candle_core::Device;
/// use meshgnn_models::point_simplifier::refinement_graph;
/// let pts = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [9.0, 9.0, 9.0]];
/// let g = refinement_graph(&pts, &[0], 3, &Device::Cpu)?;
/// let s: Vec<f32> = g.scales.flatten_all()?.to_vec1()?;
/// assert!((s[0] - (8.0f32 / 3.0).sqrt()).abs() < 1e-6); // (0 + 4 + 4) / 3
/// # Ok::<(), meshgnn_models::Error>(())
/// ```
pub fn refinement_graph(
    points: &[[f32; 3]],
    centres: &[u32],
    k: usize,
    device: &Device,
) -> Result<RefinementGraph> {
    refinement_graph_indexed(&SpatialIndex::new(points)?, points, centres, k, device)
}

/// [`refinement_graph`] with a prebuilt `index` over the same `points: #N×3` (e.g. the one
/// that built the projector's eq. 5.4 graph), so the kd-tree is built once per cloud.
/// Errors when the index covers a different number of points.
///
/// ```
/// use candle_core::Device;
/// use meshgnn_geometry::SpatialIndex;
/// use meshgnn_models::point_simplifier::refinement_graph_indexed;
/// let pts = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [9.0, 9.0, 9.0]];
/// let g = refinement_graph_indexed(&SpatialIndex::new(&pts)?, &pts, &[3], 2, &Device::Cpu)?;
/// let nb: Vec<u32> = g.neighbours.to_vec1()?;
/// assert_eq!(nb, vec![3, 1]); // itself, then the nearest (|(7, 9, 9)|² < |(9, 7, 9)|²)
/// # Ok::<(), meshgnn_models::Error>(())
/// ```
pub fn refinement_graph_indexed(
    index: &SpatialIndex,
    points: &[[f32; 3]],
    centres: &[u32],
    k: usize,
    device: &Device,
) -> Result<RefinementGraph> {
    let n = points.len();
    if index.len() != n {
        return Err(Error::Invalid {
            what: "k-NN index".into(),
            reason: format!("covers {} points, the cloud has {n}", index.len()),
        });
    }
    if let Some(&bad) = centres.iter().find(|&&c| c as usize >= n) {
        return Err(Error::Invalid {
            what: format!("centre {bad}"),
            reason: format!("out of range for {n} points"),
        });
    }
    let k = k.min(n);
    let m = centres.len();
    let centre_points: Vec<[f32; 3]> = centres
        .iter()
        .filter_map(|&c| points.get(c as usize).copied())
        .collect();
    let nn = index.knn(&centre_points, k)?;
    let mut offsets = vec![0f32; m * k * 3];
    let mut scales = vec![0f32; m];
    offsets
        .par_chunks_mut(k * 3)
        .zip(scales.par_iter_mut())
        .enumerate()
        .for_each(|(i, (off, scale))| {
            let c = centre_points.get(i).copied().unwrap_or([0.0; 3]);
            let row = nn.row(i);
            let mean_sq = row
                .iter()
                .filter_map(|&j| points.get(j as usize))
                .map(|p| (0..3).map(|d| f64::from(p[d] - c[d]).powi(2)).sum::<f64>())
                .sum::<f64>()
                / k as f64;
            let s = mean_sq.sqrt() as f32;
            *scale = s;
            let inv = if s > 0.0 { 1.0 / s } else { 0.0 };
            for (o, &j) in off.chunks_exact_mut(3).zip(row) {
                if let Some(p) = points.get(j as usize) {
                    for d in 0..3 {
                        o[d] = (p[d] - c[d]) * inv;
                    }
                }
            }
        });
    Ok(RefinementGraph {
        centres: Tensor::from_slice(centres, m, device)?,
        neighbours: Tensor::from_vec(nn.indices, m * k, device)?,
        offsets: Tensor::from_vec(offsets, (m * k, 3), device)?,
        scales: Tensor::from_vec(scales, (m, 1), device)?,
        positions: Tensor::from_vec(centre_points.into_flattened(), (m, 3), device)?,
        k,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_are_in_units_of_the_neighbourhood_radius() {
        let pts = [[1.0, 1.0, 1.0], [1.0, 1.0, 3.0], [9.0, 9.0, 9.0]];
        let g = refinement_graph(&pts, &[0, 2], 2, &Device::Cpu).unwrap();
        let off: Vec<Vec<f32>> = g.offsets.to_vec2().unwrap();
        // centre 0: neighbours 0 (itself), 1 at +2 z; s = sqrt(4/2) = √2
        let r2 = 2f32.sqrt();
        assert_eq!(off[0], vec![0.0, 0.0, 0.0]);
        assert!((off[1][2] - 2.0 / r2).abs() < 1e-6);
        let nb: Vec<u32> = g.neighbours.to_vec1().unwrap();
        assert_eq!(nb, vec![0, 1, 2, 1]);
        assert!(refinement_graph(&pts, &[3], 2, &Device::Cpu).is_err());
    }

    #[test]
    fn renumbered_to_its_support_it_reads_the_same_rows() {
        let pts: Vec<[f32; 3]> = (0..200u32)
            .map(|i| {
                let t = i as f32 * 0.61;
                [t.sin(), (0.7 * t).cos(), (i % 5) as f32 * 0.2]
            })
            .collect();
        let g = refinement_graph(&pts, &[150, 3, 77], 6, &Device::Cpu).unwrap();
        let support = g.support().unwrap();
        assert!(support.windows(2).all(|w| w[0] < w[1]));
        assert!(support.len() <= 18 && support.contains(&150));
        let compact = g.renumbered(&support).unwrap();
        let at = |t: &Tensor| t.to_vec1::<u32>().unwrap();
        for (a, b) in at(&g.neighbours).iter().zip(at(&compact.neighbours)) {
            assert_eq!(*a, support[b as usize]);
        }
        for (a, b) in at(&g.centres).iter().zip(at(&compact.centres)) {
            assert_eq!(*a, support[b as usize]);
        }
        assert!(g.renumbered(&support[1..]).is_err());
    }

    #[test]
    fn indexed_graph_equals_the_self_built_one() {
        let pts: Vec<[f32; 3]> = (0..300u32)
            .map(|i| {
                let t = i as f32 * 0.37;
                [t.sin(), (1.3 * t).cos(), (i % 7) as f32 * 0.1]
            })
            .collect();
        let centres = [0, 17, 42, 299];
        let index = SpatialIndex::new(&pts).unwrap();
        let a = refinement_graph(&pts, &centres, 15, &Device::Cpu).unwrap();
        let b = refinement_graph_indexed(&index, &pts, &centres, 15, &Device::Cpu).unwrap();
        let nb = |g: &RefinementGraph| g.neighbours.to_vec1::<u32>().unwrap();
        let off = |g: &RefinementGraph| g.offsets.to_vec2::<f32>().unwrap();
        let sc = |g: &RefinementGraph| g.scales.to_vec2::<f32>().unwrap();
        assert_eq!(nb(&a), nb(&b));
        assert_eq!(off(&a), off(&b));
        assert_eq!(sc(&a), sc(&b));
        assert_eq!(nb(&a)[0], 0);
        let other = SpatialIndex::new(&pts[..200]).unwrap();
        assert!(refinement_graph_indexed(&other, &pts, &centres, 15, &Device::Cpu).is_err());
    }
}
