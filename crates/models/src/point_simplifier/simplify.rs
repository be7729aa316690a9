//! The inference entry point: any point cloud, any target count, in its own units. Normalises
//! to the unit sphere, builds the projector graph (k-NN, k = 7, or a given mesh adjacency),
//! runs the model without autograd and maps the kept points back.

use std::time::{Duration, Instant};

use meshgnn_geometry::SpatialIndex;
use meshgnn_geometry::unit_sphere_normalization;
use meshgnn_graph::CsrMatrix;

use super::{LatentSamplingOptions, NeighbourIndex, PointSimplifier, StageTimings};
use crate::{Error, Result};

/// Options of [`PointSimplifier::simplify`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SimplifyOptions {
    /// The latent-FPS selector (cell size of the large-cloud approximation).
    pub selection: LatentSamplingOptions,
    /// Seed of the FPS start points.
    pub seed: u64,
}

/// A simplified cloud.
#[derive(Clone, Debug, PartialEq)]
pub struct Simplification {
    /// The kept points after AttRef refinement, `#M×3`, in the input's units.
    pub points: Vec<[f32; 3]>,
    /// Index in the input of the point each kept point comes from, `#M`, distinct.
    pub indices: Vec<u32>,
    /// The input normals at `indices`, when normals were given.
    pub normals: Option<Vec<[f32; 3]>>,
    /// Time per stage.
    pub timings: StageTimings,
    /// Total wall-clock time, normalisation and copies included.
    pub total: Duration,
}

impl PointSimplifier {
    /// Simplifies `points: #N×3` to exactly `target` points (`1 ≤ target ≤ N`). `normals: #N×3`
    /// are carried to the kept points (the model itself reads positions only, as the thesis);
    /// `adjacency: #N×#N` (a mesh's [`meshgnn_graph::vertex_adjacency`]) replaces the k-NN
    /// graph of the projector (ch. 5.3.2). Errors on an empty cloud, a bad target, NaN or
    /// infinite coordinates, or normals/adjacency of another size.
    ///
    /// ```
    /// use meshgnn_geometry::icosphere;
    /// use meshgnn_models::point_simplifier::{PointSimplifier, SimplifyOptions};
    /// let model: PointSimplifier = meshgnn_models::pretrained::load("point_simplifier")?;
    /// let sphere = icosphere(4).vertices().to_vec(); // 2562 points
    /// let out = model.simplify(&sphere, None, None, 128, &SimplifyOptions::default())?;
    /// assert_eq!(out.points.len(), 128);
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn simplify(
        &self,
        points: &[[f32; 3]],
        normals: Option<&[[f32; 3]]>,
        adjacency: Option<&CsrMatrix>,
        target: usize,
        options: &SimplifyOptions,
    ) -> Result<Simplification> {
        let start = Instant::now();
        let n = points.len();
        if n == 0 {
            return Err(Error::Invalid {
                what: "points".into(),
                reason: "the cloud is empty".into(),
            });
        }
        if target == 0 || target > n {
            return Err(Error::Invalid {
                what: "target count".into(),
                reason: format!("must be in 1..={n} for {n} points, got {target}"),
            });
        }
        if let Some(i) = meshgnn_geometry::vec3::first_non_finite(points) {
            return Err(Error::Invalid {
                what: format!("point {i}"),
                reason: "has a non-finite coordinate".into(),
            });
        }
        if let Some(nr) = normals
            && nr.len() != n
        {
            return Err(Error::Invalid {
                what: "normals".into(),
                reason: format!("{} normals for {n} points", nr.len()),
            });
        }
        let norm = unit_sphere_normalization(points)?;
        let unit = norm.apply(points);
        let t_knn = Instant::now();
        // A k-NN graph's cloud runs in its kd-tree's slot order (spatially coherent: the
        // queries and feature gathers stay in cache); indices are mapped back at the end.
        let (unit, order, graph) = match adjacency {
            Some(adj) => {
                if adj.rows() != n {
                    return Err(Error::Invalid {
                        what: "adjacency".into(),
                        reason: format!("{} rows for {n} points", adj.rows()),
                    });
                }
                (
                    unit,
                    None,
                    NeighbourIndex::from_adjacency(adj, self.device())?,
                )
            }
            None if n == 1 => {
                let graph = NeighbourIndex::from_rows(&[Vec::new()], self.device())?;
                (unit, None, graph)
            }
            None => {
                let k = self.config().gnn_neighbours.min(n - 1);
                let (index, order) = SpatialIndex::new(&unit)?.into_slot_order();
                let unit = index.slot_points().to_vec();
                let graph = NeighbourIndex::from_knn_index(index, k, self.device())?;
                (unit, Some(order), graph)
            }
        };
        let knn = t_knn.elapsed();
        let mut out = self.forward(
            &unit,
            &graph,
            target,
            options.selection,
            options.seed,
            false,
        )?;
        if let Some(order) = &order {
            for i in &mut out.indices {
                *i = order.get(*i as usize).copied().unwrap_or(*i);
            }
        }
        let rows: Vec<Vec<f32>> = out.points.to_vec2()?;
        let kept: Vec<[f32; 3]> = rows
            .into_iter()
            .map(|r| match r.as_slice() {
                &[x, y, z] => Ok([x, y, z]),
                _ => Err(Error::Invalid {
                    what: "model output".into(),
                    reason: format!("a row of {} values, expected 3", r.len()),
                }),
            })
            .collect::<Result<_>>()?;
        let normals = normals.map(|nr| {
            out.indices
                .iter()
                .filter_map(|&i| nr.get(i as usize).copied())
                .collect()
        });
        Ok(Simplification {
            points: norm.invert(&kept),
            indices: out.indices,
            normals,
            timings: StageTimings {
                knn: knn + out.timings.knn,
                ..out.timings
            },
            total: start.elapsed(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::{DType, Device};
    use candle_nn::{VarBuilder, VarMap};
    use meshgnn_geometry::{icosphere, vertex_normals};
    use meshgnn_graph::{
        FpsStart, centroidal_relaxation, fast_farthest_point_sampling, vertex_adjacency,
    };

    use super::super::{CENTROIDAL_STEPS, PointSimplifierConfig, SelectorSpace};

    fn model_selecting_in(selector: SelectorSpace) -> PointSimplifier {
        let map = VarMap::new();
        let vb = VarBuilder::from_varmap(&map, DType::F32, &Device::Cpu);
        let config = PointSimplifierConfig {
            selector,
            ..Default::default()
        };
        PointSimplifier::new(vb, &config).unwrap()
    }

    fn model() -> PointSimplifier {
        model_selecting_in(SelectorSpace::Latent)
    }

    #[test]
    fn position_selectors_keep_the_points_fps_and_its_relaxation_keep() {
        let pts: Vec<[f32; 3]> = icosphere(3)
            .vertices()
            .iter()
            .map(|p| [p[0] * 3.0, p[1] * 1.5 - 2.0, p[2]])
            .collect();
        let o = SimplifyOptions {
            seed: 5,
            ..Default::default()
        };
        let out = model_selecting_in(SelectorSpace::Position)
            .simplify(&pts, None, None, 40, &o)
            .unwrap();
        // the cloud runs in its kd-tree's slot order; indices come back in the input's
        let unit = unit_sphere_normalization(&pts).unwrap().apply(&pts);
        let (index, order) = SpatialIndex::new(&unit).unwrap().into_slot_order();
        let slotted = index.slot_points();
        let to_input =
            |kept: Vec<u32>| -> Vec<u32> { kept.into_iter().map(|i| order[i as usize]).collect() };
        let fps_slots = fast_farthest_point_sampling(slotted, 40, FpsStart::Seeded(5)).unwrap();
        let fps = to_input(fps_slots.clone());
        assert_eq!(out.indices, fps);
        let latent = model().simplify(&pts, None, None, 40, &o).unwrap();
        assert_ne!(
            latent.indices, fps,
            "an untrained projector is not the identity"
        );
        let centroidal = model_selecting_in(SelectorSpace::Centroidal)
            .simplify(&pts, None, None, 40, &o)
            .unwrap();
        let relaxed =
            to_input(centroidal_relaxation(slotted, &fps_slots, CENTROIDAL_STEPS).unwrap());
        assert_eq!(centroidal.indices, relaxed);
        assert_ne!(relaxed, fps);
    }

    #[test]
    fn exact_count_distinct_in_range_and_normals_follow() {
        let m = model();
        let mesh = icosphere(3);
        let pts: Vec<[f32; 3]> = mesh
            .vertices()
            .iter()
            .map(|p| [p[0] * 5.0 + 1.0, p[1] * 5.0, p[2] * 5.0])
            .collect();
        let normals = vertex_normals(&mesh);
        // one cell of the latent selector, and 8+ cells
        let cells = SimplifyOptions {
            selection: LatentSamplingOptions { cell_size: 80 },
            seed: 3,
        };
        for (target, options) in [1, 33, 300, pts.len()]
            .into_iter()
            .flat_map(|t| [(t, SimplifyOptions::default()), (t, cells)])
        {
            let out = m
                .simplify(&pts, Some(&normals), None, target, &options)
                .unwrap();
            assert_eq!(out.points.len(), target);
            let mut s = out.indices.clone();
            s.sort_unstable();
            s.dedup();
            assert_eq!(s.len(), target);
            assert!(s.iter().all(|&i| (i as usize) < pts.len()));
            let nr = out.normals.unwrap();
            for (k, &i) in out.indices.iter().enumerate() {
                assert_eq!(nr[k], normals[i as usize]);
            }
            // refined points stay near the input (in its units, radius 5)
            for (p, &i) in out.points.iter().zip(&out.indices) {
                let q = pts[i as usize];
                let d: f32 = (0..3).map(|a| (p[a] - q[a]).powi(2)).sum::<f32>().sqrt();
                assert!(d.is_finite() && d < 5.0, "moved {d}");
            }
        }
        let adj = vertex_adjacency(&mesh).unwrap();
        let out = m
            .simplify(&pts, None, Some(&adj), 50, &SimplifyOptions::default())
            .unwrap();
        assert_eq!(out.indices.len(), 50);
    }

    #[test]
    fn bad_inputs_are_errors() {
        let m = model();
        let pts = icosphere(1).vertices().to_vec();
        let o = SimplifyOptions::default();
        assert!(m.simplify(&pts, None, None, 0, &o).is_err());
        assert!(m.simplify(&pts, None, None, pts.len() + 1, &o).is_err());
        assert!(m.simplify(&[], None, None, 1, &o).is_err());
        let mut bad = pts.clone();
        bad[3][1] = f32::NAN;
        let e = m.simplify(&bad, None, None, 5, &o).unwrap_err().to_string();
        assert!(e.contains("point 3"), "{e}");
        assert!(m.simplify(&pts, Some(&pts[..3]), None, 5, &o).is_err());
        let one = m.simplify(&pts[..1], None, None, 1, &o).unwrap();
        assert_eq!(one.indices, vec![0]);
    }
}
