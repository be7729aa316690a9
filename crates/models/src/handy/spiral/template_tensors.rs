//! Everything a spiral autoencoder needs about its template, built once (thesis ch. 3.3.4,
//! Table 3.1): the mesh of every hierarchy level, the spiral sequences of every level
//! (eq. 2.28) as `u32` index tensors, and the pooling `D` / unpooling `U` between consecutive
//! levels as index and weight tensors. Converts to and from named tensors so it is stored in
//! the same safetensors file as the weights: a model file is self-contained and reloads
//! without recomputing the QEM hierarchy.
//!
//! # Stored tensors (prefix `template.` in a model file)
//! | name | dtype | shape |
//! |---|---|---|
//! | `level{i}.vertices` | f32 | `(V_i, 3)` |
//! | `level{i}.faces` | u32 | `(F_i, 3)` |
//! | `level{i}.spirals` | u32 | `(V_i, L_i)` |
//! | `level{i}.spiral_valid` | u32 | `(V_i)` real (unpadded) entries per spiral |
//! | `pool{i}.kept` | u32 | `(V_{i+1})` fine vertex kept as each coarse vertex |
//! | `pool{i}.up_indices` | u32 | `(V_i, 3)` coarse corners of each fine vertex |
//! | `pool{i}.up_weights` | f32 | `(V_i, 3)` barycentric weights |

use std::collections::HashMap;

use candle_core::{DType, Device, Tensor};
use meshgnn_geometry::TriMesh;
use meshgnn_graph::{
    Downsampling, HierarchyOptions, MeshHierarchy, PoolingMatrices, Spirals, Upsampling,
    build_hierarchy,
};

use crate::handy::spiral::{Pool, SpiralPadding, Unpool};
use crate::{Error, Result};

/// The per-level template data of a spiral autoencoder, on a device.
#[derive(Debug, Clone)]
pub struct TemplateTensors {
    hierarchy: MeshHierarchy,
    spirals: Vec<Tensor>,
    pools: Vec<Pool>,
    unpools: Vec<Unpool>,
    device: Device,
}

impl TemplateTensors {
    /// Builds the hierarchy of `template` with [`build_hierarchy`] (QEM decimation, pooling,
    /// spirals of every level) and moves it to `device`.
    ///
    /// ```
    /// use candle_core::Device;
    /// use meshgnn_graph::HierarchyOptions;
    /// use meshgnn_models::spiral::TemplateTensors;
    /// let options = HierarchyOptions { factors: vec![4.0, 4.0], spiral_lengths: vec![9; 3], dilations: vec![1; 3] };
    /// let t = TemplateTensors::new(&meshgnn_geometry::icosphere(3), &options, &Device::Cpu)?;
    /// assert_eq!(t.vertex_counts(), vec![642, 162, 42]);
    /// assert_eq!(t.spirals(0, Default::default())?.dims(), &[642 * 9]);
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn new(template: &TriMesh, options: &HierarchyOptions, device: &Device) -> Result<Self> {
        if options.spiral_lengths.is_empty() {
            return Err(Error::Invalid {
                what: "hierarchy options".into(),
                reason: "no spiral lengths: a spiral autoencoder needs spirals on every level"
                    .into(),
            });
        }
        Self::from_hierarchy(build_hierarchy(template, options)?, device)
    }

    /// Wraps a computed hierarchy; checks that every level has spirals and that the pooling
    /// indices agree with the level sizes.
    pub fn from_hierarchy(hierarchy: MeshHierarchy, device: &Device) -> Result<Self> {
        let levels = hierarchy.levels.len();
        if levels < 2 || hierarchy.pooling.len() + 1 != levels || hierarchy.spirals.len() != levels
        {
            return Err(Error::Invalid {
                what: "template hierarchy".into(),
                reason: format!(
                    "{levels} levels, {} pooling steps and {} spiral sets: need at least 2 \
                     levels, one pooling step between consecutive levels and spirals on each",
                    hierarchy.pooling.len(),
                    hierarchy.spirals.len()
                ),
            });
        }
        let spirals = hierarchy
            .levels
            .iter()
            .zip(&hierarchy.spirals)
            .enumerate()
            .map(|(level, (mesh, s))| spiral_tensor(level, mesh.vertex_count(), s, device))
            .collect::<Result<Vec<_>>>()?;
        let mut pools = Vec::with_capacity(levels - 1);
        let mut unpools = Vec::with_capacity(levels - 1);
        for (i, p) in hierarchy.pooling.iter().enumerate() {
            let (fine, coarse) = (
                hierarchy.levels[i].vertex_count(),
                hierarchy.levels[i + 1].vertex_count(),
            );
            if p.down.fine_vertices != fine
                || p.down.kept.len() != coarse
                || p.up.indices.len() != fine
                || p.up.coarse_vertices != coarse
            {
                return Err(Error::Invalid {
                    what: format!("template pooling {i}"),
                    reason: format!(
                        "maps {} → {} vertices and back {} → {}, but the levels have {fine} and \
                         {coarse}",
                        p.down.fine_vertices,
                        p.down.kept.len(),
                        p.up.coarse_vertices,
                        p.up.indices.len()
                    ),
                });
            }
            pools.push(Pool::new(&p.down.kept, fine, device)?);
            unpools.push(Unpool::new(&p.up.indices, &p.up.weights, coarse, device)?);
        }
        Ok(Self {
            hierarchy,
            spirals,
            pools,
            unpools,
            device: device.clone(),
        })
    }

    /// Number of levels (pooling steps + 1).
    pub fn level_count(&self) -> usize {
        self.hierarchy.levels.len()
    }

    /// Vertex count of every level, finest first.
    pub fn vertex_counts(&self) -> Vec<usize> {
        self.hierarchy
            .levels
            .iter()
            .map(TriMesh::vertex_count)
            .collect()
    }

    /// Spiral length `L_i` of every level.
    pub fn spiral_lengths(&self) -> Vec<usize> {
        self.hierarchy.spirals.iter().map(|s| s.length).collect()
    }

    /// The full-resolution template (level 0).
    pub fn template(&self) -> &TriMesh {
        &self.hierarchy.levels[0]
    }

    /// The plain-data hierarchy (meshes, pooling, spirals) this was built from.
    pub fn hierarchy(&self) -> &MeshHierarchy {
        &self.hierarchy
    }

    /// The device the tensors live on.
    pub fn device(&self) -> &Device {
        &self.device
    }

    /// Spirals of `level` as the flat `(V·L)` `u32` tensor [`crate::handy::spiral::SpiralConv`]
    /// takes; with [`SpiralPadding::Zero`] the padded entries become the pad index `V`.
    pub fn spirals(&self, level: usize, padding: SpiralPadding) -> Result<Tensor> {
        let tensor = self
            .spirals
            .get(level)
            .ok_or_else(|| level_error(level, self))?;
        match padding {
            SpiralPadding::Repeat => Ok(tensor.clone()),
            SpiralPadding::Zero => {
                let s = &self.hierarchy.spirals[level];
                let pad = s.len() as u32;
                let indices: Vec<u32> = s
                    .indices
                    .chunks(s.length.max(1))
                    .zip(&s.valid)
                    .flat_map(|(row, &valid)| {
                        row.iter()
                            .enumerate()
                            .map(move |(k, &i)| if k < valid as usize { i } else { pad })
                    })
                    .collect();
                Ok(Tensor::from_vec(indices, s.indices.len(), &self.device)?)
            }
        }
    }

    /// Pooling `D` from `level` to `level + 1`.
    pub fn pool(&self, level: usize) -> Result<&Pool> {
        self.pools
            .get(level)
            .ok_or_else(|| level_error(level, self))
    }

    /// Unpooling `U` from `level + 1` back to `level`.
    pub fn unpool(&self, level: usize) -> Result<&Unpool> {
        self.unpools
            .get(level)
            .ok_or_else(|| level_error(level, self))
    }

    /// The stored tensors (table in the module docs), names prefixed by `prefix`.
    ///
    /// ```
    /// use candle_core::Device;
    /// use meshgnn_graph::HierarchyOptions;
    /// use meshgnn_models::spiral::TemplateTensors;
    /// let options = HierarchyOptions { factors: vec![4.0], spiral_lengths: vec![9; 2], dilations: vec![1; 2] };
    /// let t = TemplateTensors::new(&meshgnn_geometry::icosphere(2), &options, &Device::Cpu)?;
    /// let named = t.to_named_tensors("template.")?;
    /// assert_eq!(named.len(), 11);
    /// let back = TemplateTensors::from_named_tensors(&named, "template.", &Device::Cpu)?;
    /// assert_eq!(back.hierarchy(), t.hierarchy());
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn to_named_tensors(&self, prefix: &str) -> Result<HashMap<String, Tensor>> {
        let cpu = Device::Cpu;
        let mut out = HashMap::new();
        for (i, (mesh, s)) in self
            .hierarchy
            .levels
            .iter()
            .zip(&self.hierarchy.spirals)
            .enumerate()
        {
            let v = mesh.vertex_count();
            let vertices: Vec<f32> = mesh.vertices().iter().flatten().copied().collect();
            let faces: Vec<u32> = mesh.triangles().iter().flatten().copied().collect();
            let name = |field: &str| format!("{prefix}level{i}.{field}");
            out.insert(name("vertices"), Tensor::from_vec(vertices, (v, 3), &cpu)?);
            out.insert(
                name("faces"),
                Tensor::from_vec(faces, (mesh.face_count(), 3), &cpu)?,
            );
            out.insert(
                name("spirals"),
                Tensor::from_slice(&s.indices, (v, s.length), &cpu)?,
            );
            out.insert(name("spiral_valid"), Tensor::from_slice(&s.valid, v, &cpu)?);
        }
        for (i, p) in self.hierarchy.pooling.iter().enumerate() {
            let n = p.up.indices.len();
            let name = |field: &str| format!("{prefix}pool{i}.{field}");
            out.insert(
                name("kept"),
                Tensor::from_slice(&p.down.kept, p.down.kept.len(), &cpu)?,
            );
            let indices: Vec<u32> = p.up.indices.iter().flatten().copied().collect();
            let weights: Vec<f32> = p.up.weights.iter().flatten().copied().collect();
            out.insert(name("up_indices"), Tensor::from_vec(indices, (n, 3), &cpu)?);
            out.insert(name("up_weights"), Tensor::from_vec(weights, (n, 3), &cpu)?);
        }
        Ok(out)
    }

    /// Rebuilds the template from the tensors of [`TemplateTensors::to_named_tensors`],
    /// validating every index; a missing or malformed tensor is an error naming it.
    pub fn from_named_tensors(
        tensors: &HashMap<String, Tensor>,
        prefix: &str,
        device: &Device,
    ) -> Result<Self> {
        let mut levels = Vec::new();
        let mut spirals = Vec::new();
        while tensors.contains_key(&format!("{prefix}level{}.vertices", levels.len())) {
            let i = levels.len();
            let name = |field: &str| format!("{prefix}level{i}.{field}");
            let (vertices, v) = read_f32_rows(tensors, &name("vertices"), Some(3))?;
            let (faces, _) = read_u32_rows(tensors, &name("faces"), Some(3))?;
            let mesh = TriMesh::new(
                vertices.chunks(3).map(|c| [c[0], c[1], c[2]]).collect(),
                faces.chunks(3).map(|c| [c[0], c[1], c[2]]).collect(),
            )?;
            let (indices, rows) = read_u32_rows(tensors, &name("spirals"), None)?;
            let (valid, valid_rows) = read_u32_rows(tensors, &name("spiral_valid"), None)?;
            if rows != v || valid_rows != v || valid.len() != v {
                return Err(malformed(
                    &name("spirals"),
                    format!("{rows} spirals and {valid_rows} valid counts for {v} vertices"),
                ));
            }
            let length = indices.len() / v.max(1);
            spirals.push(Spirals {
                length,
                indices,
                valid,
            });
            levels.push(mesh);
        }
        if levels.is_empty() {
            return Err(missing(&format!("{prefix}level0.vertices")));
        }
        let mut pooling = Vec::with_capacity(levels.len() - 1);
        for i in 0..levels.len() - 1 {
            let name = |field: &str| format!("{prefix}pool{i}.{field}");
            let (kept, _) = read_u32_rows(tensors, &name("kept"), None)?;
            let (up_indices, _) = read_u32_rows(tensors, &name("up_indices"), Some(3))?;
            let (up_weights, _) = read_f32_rows(tensors, &name("up_weights"), Some(3))?;
            pooling.push(PoolingMatrices {
                down: Downsampling {
                    kept,
                    fine_vertices: levels[i].vertex_count(),
                },
                up: Upsampling {
                    indices: up_indices.chunks(3).map(|c| [c[0], c[1], c[2]]).collect(),
                    weights: up_weights.chunks(3).map(|c| [c[0], c[1], c[2]]).collect(),
                    coarse_vertices: levels[i + 1].vertex_count(),
                },
            });
        }
        Self::from_hierarchy(
            MeshHierarchy {
                levels,
                pooling,
                spirals,
            },
            device,
        )
    }
}

/// The `(V·L)` spiral tensor of one level, checking every entry and valid count.
fn spiral_tensor(level: usize, vertices: usize, s: &Spirals, device: &Device) -> Result<Tensor> {
    let bad = |reason: String| Error::Invalid {
        what: format!("template level {level} spirals"),
        reason,
    };
    if s.length == 0 || s.indices.len() != vertices * s.length || s.valid.len() != vertices {
        return Err(bad(format!(
            "{} indices of length {} and {} valid counts for {vertices} vertices",
            s.indices.len(),
            s.length,
            s.valid.len()
        )));
    }
    if let Some(k) = s.indices.iter().position(|&i| i as usize >= vertices) {
        return Err(bad(format!(
            "vertex {} has entry {} >= {vertices}",
            k / s.length,
            s.indices[k]
        )));
    }
    if let Some(v) = s
        .valid
        .iter()
        .position(|&n| n == 0 || n as usize > s.length)
    {
        return Err(bad(format!(
            "vertex {v} claims {} real entries, outside 1..={}",
            s.valid[v], s.length
        )));
    }
    Ok(Tensor::from_slice(&s.indices, s.indices.len(), device)?)
}

fn level_error(level: usize, t: &TemplateTensors) -> Error {
    Error::Invalid {
        what: format!("template level {level}"),
        reason: format!("the template has {} levels", t.level_count()),
    }
}

fn missing(name: &str) -> Error {
    Error::Invalid {
        what: format!("tensor `{name}`"),
        reason: "missing from the model file".into(),
    }
}

fn malformed(name: &str, reason: String) -> Error {
    Error::Invalid {
        what: format!("tensor `{name}`"),
        reason,
    }
}

/// The tensor `name` as `(rows, columns)` data of `dtype`; `columns` checked when given.
fn read_rows(
    tensors: &HashMap<String, Tensor>,
    name: &str,
    dtype: DType,
    columns: Option<usize>,
) -> Result<(Tensor, usize)> {
    let t = tensors.get(name).ok_or_else(|| missing(name))?;
    if t.dtype() != dtype {
        return Err(malformed(
            name,
            format!("dtype {:?}, expected {dtype:?}", t.dtype()),
        ));
    }
    let rows = match (t.dims(), columns) {
        ([n], None) => *n,
        ([n, _], None) => *n,
        ([n, c], Some(expected)) if *c == expected => *n,
        (dims, _) => {
            return Err(malformed(
                name,
                format!("shape {dims:?}, expected (N, {})", columns.unwrap_or(0)),
            ));
        }
    };
    Ok((t.flatten_all()?.to_device(&Device::Cpu)?, rows))
}

fn read_u32_rows(
    tensors: &HashMap<String, Tensor>,
    name: &str,
    columns: Option<usize>,
) -> Result<(Vec<u32>, usize)> {
    let (t, rows) = read_rows(tensors, name, DType::U32, columns)?;
    Ok((t.to_vec1::<u32>()?, rows))
}

fn read_f32_rows(
    tensors: &HashMap<String, Tensor>,
    name: &str,
    columns: Option<usize>,
) -> Result<(Vec<f32>, usize)> {
    let (t, rows) = read_rows(tensors, name, DType::F32, columns)?;
    Ok((t.to_vec1::<f32>()?, rows))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn named_tensor_round_trip_and_errors() {
        let options = HierarchyOptions {
            factors: vec![4.0, 4.0],
            spiral_lengths: vec![9, 7, 5],
            dilations: vec![1, 2, 1],
        };
        let t =
            TemplateTensors::new(&meshgnn_geometry::icosphere(2), &options, &Device::Cpu).unwrap();
        assert_eq!(t.spiral_lengths(), vec![9, 7, 5]);
        let named = t.to_named_tensors("p.").unwrap();
        assert_eq!(named.len(), 4 * 3 + 3 * 2);
        assert_eq!(named["p.level1.spirals"].dims(), &[42, 7]);
        assert_eq!(named["p.pool1.up_weights"].dims(), &[42, 3]);
        let back = TemplateTensors::from_named_tensors(&named, "p.", &Device::Cpu).unwrap();
        assert_eq!(back.hierarchy(), t.hierarchy());
        for level in 0..3 {
            assert_eq!(
                back.spirals(level, SpiralPadding::Repeat)
                    .unwrap()
                    .to_vec1::<u32>()
                    .unwrap(),
                t.hierarchy().spirals[level].indices
            );
        }
        let mut broken = named.clone();
        broken.remove("p.pool0.kept");
        let err = TemplateTensors::from_named_tensors(&broken, "p.", &Device::Cpu).unwrap_err();
        assert!(err.to_string().contains("p.pool0.kept"), "{err}");
        let mut broken = named.clone();
        let spirals = named["p.level0.spirals"]
            .affine(1.0, 1000.0)
            .unwrap()
            .to_dtype(DType::U32)
            .unwrap();
        broken.insert("p.level0.spirals".into(), spirals);
        assert!(TemplateTensors::from_named_tensors(&broken, "p.", &Device::Cpu).is_err());
        let mut broken = named;
        broken.insert(
            "p.level0.faces".into(),
            Tensor::zeros((3, 3), DType::F32, &Device::Cpu).unwrap(),
        );
        assert!(TemplateTensors::from_named_tensors(&broken, "p.", &Device::Cpu).is_err());
        assert!(t.pool(2).is_err() && t.spirals(3, SpiralPadding::Repeat).is_err());
    }

    #[test]
    fn zero_padding_uses_the_pad_index() {
        // icosphere(0) has 12 vertices: length 14 spirals need 2+ padded entries each.
        let options = HierarchyOptions {
            factors: vec![2.0],
            spiral_lengths: vec![14, 3],
            dilations: vec![1, 1],
        };
        let t =
            TemplateTensors::new(&meshgnn_geometry::icosphere(1), &options, &Device::Cpu).unwrap();
        let s = &t.hierarchy().spirals[0];
        let zero = t
            .spirals(0, SpiralPadding::Zero)
            .unwrap()
            .to_vec1::<u32>()
            .unwrap();
        let v = s.len() as u32;
        for (row, (z, valid)) in s.indices.chunks(14).zip(zero.chunks(14).zip(&s.valid)) {
            for k in 0..14 {
                let expected = if k < *valid as usize { row[k] } else { v };
                assert_eq!(z[k], expected);
            }
        }
    }
}
