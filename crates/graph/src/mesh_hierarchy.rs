//! The multi-resolution template of a spiral mesh autoencoder (thesis ch. 3.3.4, Table 3.1:
//! 28431 → 5687 → 1138 → 228 → 46 vertices; COMA, Ranjan et al. ECCV 2018; Neural3DMM,
//! Bouritsas et al. ICCV 2019): each level is a QEM decimation of the previous one that keeps
//! original vertex positions, with the pooling `D`/`U` between consecutive levels and the spiral
//! sequences (eq. 2.28) of every level. Computed once per template.

use meshgnn_geometry::{TriMesh, mesh_report};

use crate::error::{Error, Result};
use crate::{
    DecimationOptions, PoolingMatrices, Spirals, StopReason, Target, decimate, pooling_matrices,
    spiral_sequences,
};

/// Options of [`build_hierarchy`]; update with `..Default::default()`.
#[derive(Debug, Clone, PartialEq)]
pub struct HierarchyOptions {
    /// Reduction factor of the face (≈ vertex) count from each level to the next; one entry
    /// per pooling step. Default `[4, 4, 4, 4]` (COMA; the thesis uses ~5).
    pub factors: Vec<f64>,
    /// Spiral length of each level: one value for every level, one per level
    /// (`factors.len() + 1` entries), or empty for no spirals. Default `[9]` (Neural3DMM), so
    /// the default follows any number of factors.
    pub spiral_lengths: Vec<usize>,
    /// Spiral dilation of each level: one value for every level or one per level. Default
    /// `[1]`.
    pub dilations: Vec<usize>,
}

impl HierarchyOptions {
    /// The spiral length and dilation of `level`, or `None` when no spirals are asked for.
    pub fn spiral_of_level(&self, level: usize) -> Option<(usize, usize)> {
        let at = |values: &[usize]| match values {
            [one] => Some(*one),
            many => many.get(level).copied(),
        };
        Some((at(&self.spiral_lengths)?, at(&self.dilations)?))
    }
}

impl Default for HierarchyOptions {
    fn default() -> Self {
        Self {
            factors: vec![4.0; 4],
            spiral_lengths: vec![9],
            dilations: vec![1],
        }
    }
}

/// Every level of the hierarchy, finest first.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshHierarchy {
    /// `levels[0]` is the template; `levels[i + 1]` is the decimation of `levels[i]`.
    pub levels: Vec<TriMesh>,
    /// `pooling[i]`: `D` from level `i` to `i + 1` and `U` back.
    pub pooling: Vec<PoolingMatrices>,
    /// `spirals[i]`: the spiral sequences of level `i` (empty when no lengths were given).
    pub spirals: Vec<Spirals>,
}

/// Builds the mesh hierarchy of `template` (ch. 3.3.4): `factors.len()` QEM decimations with
/// `keep_original_positions`, their pooling matrices, and the spirals of each level. A level
/// whose decimation runs out of valid collapses is kept when it is within 10 % (at least 2
/// faces) of its target.
///
/// Errors, naming the problem, when the template is empty, non-manifold, has several connected
/// components, or too few vertices for the requested levels, or when the options disagree.
///
/// ```
/// use meshgnn_graph::{build_hierarchy, HierarchyOptions};
/// let options = HierarchyOptions { factors: vec![4.0, 4.0], spiral_lengths: vec![9; 3], dilations: vec![1; 3] };
/// let h = build_hierarchy(&meshgnn_geometry::icosphere(3), &options)?;
/// let faces: Vec<usize> = h.levels.iter().map(|m| m.face_count()).collect();
/// assert_eq!(faces, vec![1280, 320, 80]);
/// assert_eq!(h.spirals[2].row(0).len(), 9);
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn build_hierarchy(template: &TriMesh, options: &HierarchyOptions) -> Result<MeshHierarchy> {
    validate(template, options)?;
    let mut levels = vec![template.clone()];
    let mut pooling = Vec::with_capacity(options.factors.len());
    for (level, &factor) in options.factors.iter().enumerate() {
        let fine = &levels[level];
        let target = (fine.face_count() as f64 / factor).round() as usize;
        let decimation = decimate(
            fine,
            &DecimationOptions {
                target: Target::Faces(target),
                keep_original_positions: true,
                ..Default::default()
            },
        )?;
        let close_enough = decimation.mesh.face_count() <= target + level_slack(target);
        if decimation.stop_reason != StopReason::TargetReached && !close_enough {
            return Err(Error::UnusableMesh {
                what: format!("hierarchy level {}", level + 1),
                message: format!(
                    "decimation of {} faces stopped at {} faces instead of {target} ({}); use \
                     smaller factors or fewer levels",
                    fine.face_count(),
                    decimation.mesh.face_count(),
                    decimation.stop_reason.as_str()
                ),
            });
        }
        pooling.push(pooling_matrices(fine, &decimation)?);
        levels.push(decimation.mesh);
    }
    let spirals = levels
        .iter()
        .enumerate()
        .filter_map(|(level, mesh)| {
            let (length, dilation) = options.spiral_of_level(level)?;
            Some(spiral_sequences(mesh, length, dilation))
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(MeshHierarchy {
        levels,
        pooling,
        spirals,
    })
}

/// Faces a level may keep above its target when no valid collapse is left: 10 % of the
/// target, at least 2 (a small bordered template such as a 717-vertex hand can stop one
/// face short of a coarse target; the pooling follows the actual decimation).
fn level_slack(target: usize) -> usize {
    (target / 10).max(2)
}

fn validate(template: &TriMesh, options: &HierarchyOptions) -> Result<()> {
    if let Some((i, f)) = options
        .factors
        .iter()
        .enumerate()
        .find(|(_, f)| !(f.is_finite() && **f > 1.0))
    {
        return Err(Error::InvalidParameter {
            name: "factors",
            message: format!("factor {i} is {f}; each must be a finite number > 1"),
        });
    }
    let levels = options.factors.len() + 1;
    if !matches!(options.spiral_lengths.len(), 0 | 1) && options.spiral_lengths.len() != levels {
        return Err(Error::ShapeMismatch {
            what: "spiral lengths (one for every level, one per level, or none)",
            expected: levels,
            actual: options.spiral_lengths.len(),
        });
    }
    if !options.spiral_lengths.is_empty()
        && options.dilations.len() != 1
        && options.dilations.len() != levels
    {
        return Err(Error::ShapeMismatch {
            what: "dilations (one for every level, or one per level)",
            expected: levels,
            actual: options.dilations.len(),
        });
    }
    if template.face_count() == 0 {
        return Err(Error::Empty {
            what: "hierarchy template (no triangles)",
        });
    }
    let report = mesh_report(template);
    let what = || "hierarchy template".to_string();
    if !report.edge_manifold {
        return Err(Error::UnusableMesh {
            what: what(),
            message: format!(
                "{} edges have three or more faces; repair the mesh to a manifold first",
                report.non_manifold_edges
            ),
        });
    }
    if report.components != 1 {
        return Err(Error::UnusableMesh {
            what: what(),
            message: format!(
                "{} connected components; a template must be one connected surface",
                report.components
            ),
        });
    }
    let product: f64 = options.factors.iter().product();
    let coarsest = template.vertex_count() as f64 / product;
    if coarsest < 4.0 {
        return Err(Error::UnusableMesh {
            what: what(),
            message: format!(
                "{} vertices / {product} (product of the factors) leaves {coarsest:.1} < 4 \
                 vertices at the coarsest level; use fewer levels or smaller factors",
                template.vertex_count()
            ),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshgnn_geometry::icosphere;

    fn two_levels() -> HierarchyOptions {
        HierarchyOptions {
            factors: vec![4.0],
            spiral_lengths: vec![9, 9],
            dilations: vec![1, 1],
        }
    }

    #[test]
    fn defaults_follow_the_number_of_factors() {
        let template = icosphere(4);
        for count in [1, 2, 3] {
            let options = HierarchyOptions {
                factors: vec![4.0; count],
                ..Default::default()
            };
            let h = build_hierarchy(&template, &options).unwrap();
            assert_eq!((h.levels.len(), h.spirals.len()), (count + 1, count + 1));
            assert!(h.spirals.iter().all(|s| s.row(0).len() == 9));
        }
        // One entry per level still works; a count that fits neither is refused.
        let per_level = HierarchyOptions {
            factors: vec![4.0, 4.0],
            spiral_lengths: vec![9, 7, 5],
            dilations: vec![1, 1, 2],
        };
        let h = build_hierarchy(&template, &per_level).unwrap();
        let lengths: Vec<usize> = h.spirals.iter().map(|s| s.row(0).len()).collect();
        assert_eq!(lengths, [9, 7, 5]);
        let wrong = HierarchyOptions {
            spiral_lengths: vec![9, 9],
            ..per_level
        };
        assert!(matches!(
            build_hierarchy(&template, &wrong),
            Err(Error::ShapeMismatch {
                expected: 3,
                actual: 2,
                ..
            })
        ));
        let none = HierarchyOptions {
            factors: vec![4.0],
            spiral_lengths: vec![],
            dilations: vec![],
        };
        assert!(
            build_hierarchy(&template, &none)
                .unwrap()
                .spirals
                .is_empty()
        );
    }

    #[test]
    fn a_level_may_stop_a_tenth_above_its_target_at_least_two_faces() {
        assert_eq!([5, 22, 29, 300].map(level_slack), [2, 2, 2, 30]);
    }

    #[test]
    fn two_level_hierarchy_has_consistent_pooling() {
        let template = icosphere(4);
        let h = build_hierarchy(&template, &two_levels()).unwrap();
        assert_eq!(h.levels.len(), 2);
        assert_eq!(h.levels[1].face_count(), 1280);
        let (d, u) = (&h.pooling[0].down, &h.pooling[0].up);
        assert_eq!(d.kept.len(), h.levels[1].vertex_count());
        assert_eq!(u.indices.len(), template.vertex_count());
        // U·D restricted to kept vertices is the identity, rows of U are convex weights.
        let x: Vec<f32> = (0..template.vertex_count()).map(|i| i as f32).collect();
        let back = u.apply(&d.apply(&x, 1).unwrap(), 1).unwrap();
        for &i in &d.kept {
            assert_eq!(back[i as usize], i as f32);
        }
        for w in &u.weights {
            assert!(w.iter().all(|&x| (0.0..=1.0).contains(&x)));
            assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        }
        assert_eq!(h.spirals[1].len(), h.levels[1].vertex_count());
    }

    #[test]
    fn default_four_levels_reduce_about_four_times_each() {
        let h = build_hierarchy(&icosphere(5), &HierarchyOptions::default()).unwrap();
        let v: Vec<usize> = h.levels.iter().map(|m| m.vertex_count()).collect();
        assert_eq!(v[0], 10242);
        for k in 0..4 {
            let ratio = v[k] as f64 / v[k + 1] as f64;
            assert!((3.5..4.5).contains(&ratio), "{v:?}");
        }
        assert_eq!(h.pooling.len(), 4);
        assert_eq!(h.spirals.len(), 5);
    }

    #[test]
    fn unusable_templates_are_named_errors() {
        // Two spheres.
        let a = icosphere(2);
        let n = a.vertex_count() as u32;
        let mut v = a.vertices().to_vec();
        v.extend(a.vertices().iter().map(|p| [p[0] + 3.0, p[1], p[2]]));
        let mut t = a.triangles().to_vec();
        t.extend(a.triangles().iter().map(|f| f.map(|i| i + n)));
        let two = TriMesh::new(v, t).unwrap();
        let err = build_hierarchy(&two, &two_levels()).unwrap_err();
        assert!(err.to_string().contains("2 connected components"), "{err}");
        // Three triangles on one edge.
        let fan = TriMesh::new(
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, -1.0, 0.0],
                [0.0, 0.0, 1.0],
            ],
            vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]],
        )
        .unwrap();
        let err = build_hierarchy(&fan, &two_levels()).unwrap_err();
        assert!(err.to_string().contains("three or more faces"), "{err}");
        // Too small for four levels of 4x.
        let err = build_hierarchy(&icosphere(1), &HierarchyOptions::default()).unwrap_err();
        assert!(err.to_string().contains("coarsest level"), "{err}");
        let empty = TriMesh::new(vec![], vec![]).unwrap();
        assert!(matches!(
            build_hierarchy(&empty, &two_levels()),
            Err(Error::Empty { .. })
        ));
        let bad = HierarchyOptions {
            factors: vec![0.5],
            ..two_levels()
        };
        assert!(matches!(
            build_hierarchy(&icosphere(3), &bad),
            Err(Error::InvalidParameter { .. })
        ));
    }
}
