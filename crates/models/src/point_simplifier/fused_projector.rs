//! The projector of thesis ch. 5.3.2 at inference, in plain Rust: the point-wise layers
//! (`Linear → BatchNorm → ReLU`, batch norm folded into the linear map) run fused row by row,
//! so each point's 64-channel intermediates stay in registers and L1 instead of being written
//! and re-read as `N × 64` tensors ([`FusedProjector::pointwise`]); then eq. 5.4 at the rows
//! asked — all of them for the latent selector, the points AttRef reads otherwise — with the
//! neighbour mean, the two linear maps and the ReLU fused per row
//! ([`FusedProjector::aggregate`]). Chunks of points run in parallel with rayon; every row is
//! computed the same way whatever the thread count and whichever rows are asked, so results
//! are deterministic. Used only without autograd (plain, non-trainable weights on the CPU).

use candle_core::Tensor;
use meshgnn_graph::CsrMatrix;
use rayon::prelude::*;

use crate::{Error, Result};

/// Output channels computed together (four 4-lane or two 8-lane vector registers).
const TILE: usize = 16;

/// Points per parallel task.
const CHUNK: usize = 4096;

/// An affine map `y = W x + b` packed for row-at-a-time products: `W` stored as tiles of
/// [`TILE`] output channels, each tile `input × TILE` contiguous (zero-padded at the end).
#[derive(Clone, Debug)]
pub(crate) struct HostAffine {
    packed: Vec<[f32; TILE]>,
    bias: Vec<f32>,
    input: usize,
    output: usize,
}

impl HostAffine {
    /// From `wt: (C_in, C_out)` (the transposed weight, contiguous) and `bias: (C_out)`
    /// (`None`: zero).
    pub(crate) fn from_transposed(wt: &Tensor, bias: Option<&Tensor>) -> Result<Self> {
        let (input, output) = wt.dims2()?;
        let values: Vec<f32> = wt.flatten_all()?.to_vec1()?;
        let bias: Vec<f32> = match bias {
            Some(b) => b.flatten_all()?.to_vec1()?,
            None => vec![0.0; output],
        };
        if bias.len() != output {
            return Err(Error::Invalid {
                what: "host affine bias".into(),
                reason: format!("{} values for {output} output channels", bias.len()),
            });
        }
        let tiles = output.div_ceil(TILE);
        let mut packed = vec![[0.0f32; TILE]; tiles * input];
        for (i, row) in values.chunks_exact(output.max(1)).enumerate() {
            for (o, &w) in row.iter().enumerate() {
                if let Some(slot) = packed
                    .get_mut((o / TILE) * input + i)
                    .and_then(|t| t.get_mut(o % TILE))
                {
                    *slot = w;
                }
            }
        }
        Ok(Self {
            packed,
            bias,
            input,
            output,
        })
    }

    /// The map of a candle `Linear` (`y = x Wᵀ + b`), detached.
    pub(crate) fn from_linear(linear: &candle_nn::Linear) -> Result<Self> {
        Self::from_transposed(
            &linear.weight().detach().t()?.contiguous()?,
            linear.bias().map(|b| b.detach()).as_ref(),
        )
    }

    /// Input channels `C_in`.
    pub(crate) fn input(&self) -> usize {
        self.input
    }

    /// Output channels `C_out`.
    pub(crate) fn output(&self) -> usize {
        self.output
    }

    /// `y = W x + b` for one row: `x: #C_in`, `y: #C_out` (overwritten).
    #[inline(always)]
    pub(crate) fn apply(&self, x: &[f32], y: &mut [f32]) {
        y.copy_from_slice(&self.bias);
        self.accumulate(x, y);
    }

    /// [`HostAffine::apply`] on the rows of `xs` (row `r` starts at `r · stride`; its first
    /// `C_in` values are read) into `ys: #rows × C_out`, [`ROW_GROUP`] rows at a time: their
    /// accumulators are independent chains. Every output is summed exactly as `apply` sums it.
    #[inline(always)]
    pub(crate) fn apply_strided(&self, xs: &[f32], stride: usize, ys: &mut [f32]) {
        let output = self.output.max(1);
        for (g, ys) in ys.chunks_mut(ROW_GROUP * output).enumerate() {
            let row = |r: usize| &xs[(g * ROW_GROUP + r) * stride..][..self.input];
            match ys.len() / output {
                4 => self.apply_rows::<4>(std::array::from_fn(row), ys),
                3 => self.apply_rows::<3>(std::array::from_fn(row), ys),
                2 => self.apply_rows::<2>(std::array::from_fn(row), ys),
                _ => self.apply_rows::<1>([row(0)], ys),
            }
        }
    }

    /// `ys[r] = W xs[r] + b` for `R` rows (`ys: #R × C_out`), tile by tile.
    #[inline(always)]
    fn apply_rows<const R: usize>(&self, xs: [&[f32]; R], ys: &mut [f32]) {
        let input = self.input.max(1);
        let n = xs.iter().fold(input, |n, x| n.min(x.len()));
        let xs: [&[f32]; R] = std::array::from_fn(|r| &xs[r][..n]);
        for (t, tile) in self.packed.chunks_exact(input).enumerate() {
            let mut acc = [[0.0f32; TILE]; R];
            for (i, w) in tile[..n].iter().enumerate() {
                for (a, x) in acc.iter_mut().zip(&xs) {
                    let xi = x[i];
                    for (ak, &wk) in a.iter_mut().zip(w) {
                        *ak += xi * wk;
                    }
                }
            }
            let first = t * TILE;
            let width = TILE.min(self.output.saturating_sub(first));
            let bias = &self.bias[first..first + width];
            for (y, a) in ys.chunks_exact_mut(self.output.max(1)).zip(&acc) {
                for ((yo, &b), &a) in y[first..first + width].iter_mut().zip(bias).zip(a) {
                    *yo = b + a;
                }
            }
        }
    }

    /// `y += W x` for one row: `x: #C_in`, `y: #C_out`. Up to [`TILE_GROUP`] tiles at once: their
    /// accumulators are independent chains, so the adds of one wait on no other (one tile
    /// alone is bound by the add latency). Each output still sums `x_i w_i` in input order.
    #[inline(always)]
    fn accumulate(&self, x: &[f32], y: &mut [f32]) {
        let input = self.input.max(1);
        for (group, y_group) in self
            .packed
            .chunks(TILE_GROUP * input)
            .zip(y.chunks_mut(TILE_GROUP * TILE))
        {
            match group.len() / input {
                4 => accumulate_tiles::<4>(group, input, x, y_group),
                3 => accumulate_tiles::<3>(group, input, x, y_group),
                2 => accumulate_tiles::<2>(group, input, x, y_group),
                _ => accumulate_tiles::<1>(group, input, x, y_group),
            }
        }
    }
}

/// Tiles of output channels accumulated together by [`HostAffine::accumulate`].
const TILE_GROUP: usize = 4;

/// Rows mapped together by [`HostAffine::apply_strided`].
const ROW_GROUP: usize = 4;

/// `y += W x` over `G` consecutive packed tiles (`G · input` rows of `TILE` weights).
#[inline(always)]
fn accumulate_tiles<const G: usize>(tiles: &[[f32; TILE]], input: usize, x: &[f32], y: &mut [f32]) {
    let n = input.min(x.len());
    let tiles: [&[[f32; TILE]]; G] = std::array::from_fn(|g| &tiles[g * input..g * input + n]);
    let mut acc = [[0.0f32; TILE]; G];
    for (i, &xi) in x[..n].iter().enumerate() {
        for (a, tile) in acc.iter_mut().zip(&tiles) {
            for (ak, &wk) in a.iter_mut().zip(&tile[i]) {
                *ak += xi * wk;
            }
        }
    }
    for (y_tile, a) in y.chunks_mut(TILE).zip(acc) {
        for (yo, a) in y_tile.iter_mut().zip(a) {
            *yo += a;
        }
    }
}

/// The projector's evaluation-mode maps: point-wise layers, then eq. 5.4's `W_c` (+ b) and `W_n`.
#[derive(Clone, Debug)]
pub(crate) struct FusedProjector {
    pub(crate) layers: Vec<HostAffine>,
    pub(crate) centre: HostAffine,
    pub(crate) neighbour: HostAffine,
}

impl FusedProjector {
    /// The point-wise layers (batch norm folded, ReLU) on every point: `#N × C` row-major.
    pub(crate) fn pointwise(&self, points: &[[f32; 3]]) -> Result<Vec<f32>> {
        let c = self.channels()?;
        let scratch = self
            .layers
            .iter()
            .map(|l| l.output)
            .chain([3, c])
            .max()
            .unwrap_or(c);
        // The row loops are compiled once per instruction set and dispatched at run time (AVX2
        // where the CPU has it): the same arithmetic in the same order, in wider registers.
        let arch = pulp::Arch::new();
        let mut features = vec![0.0f32; points.len() * c];
        features
            .par_chunks_mut(CHUNK * c)
            .zip(points.par_chunks(CHUNK))
            .for_each_init(
                || {
                    let rows = ROW_GROUP * scratch;
                    (vec![0.0f32; rows], vec![0.0f32; rows])
                },
                |(a, b), (rows, points)| {
                    arch.dispatch(PointwiseRows {
                        layers: &self.layers,
                        channels: c,
                        points,
                        rows,
                        scratch: (a, b),
                    })
                },
            );
        Ok(features)
    }

    /// Eq. 5.4 at the points `rows` (indices into the cloud): their embeddings `#R × C`
    /// (row-major), from every point's point-wise `features: #N × C` and `mean: #R × N`, the
    /// rows' part of the projector graph's mean operator
    /// ([`super::NeighbourIndex::mean_rows`]). Each row is computed the same way whichever
    /// rows are asked.
    pub(crate) fn aggregate(
        &self,
        features: &[f32],
        mean: &CsrMatrix,
        rows: &[u32],
    ) -> Result<Vec<f32>> {
        let c = self.channels()?;
        let n = features.len() / c;
        if features.len() != n * c || mean.rows() != rows.len() || mean.cols() != n {
            return Err(Error::Invalid {
                what: "projector graph".into(),
                reason: format!(
                    "a {}×{} mean operator for {} rows of {} features of {c} channels",
                    mean.rows(),
                    mean.cols(),
                    rows.len(),
                    features.len() as f64 / c as f64
                ),
            });
        }
        if let Some(&bad) = rows.iter().find(|&&r| r as usize >= n) {
            return Err(Error::Invalid {
                what: format!("row {bad}"),
                reason: format!("out of range for {n} points"),
            });
        }
        let arch = pulp::Arch::new();
        let mut embeddings = vec![0.0f32; rows.len() * c];
        embeddings
            .par_chunks_mut(CHUNK * c)
            .zip(rows.par_chunks(CHUNK))
            .enumerate()
            .for_each_init(
                || (vec![0.0f64; c], vec![0.0f32; c]),
                |(sum, mean_row), (chunk, (out, centres))| {
                    arch.dispatch(GnnRows {
                        projector: self,
                        channels: c,
                        features,
                        mean_operator: mean,
                        first_row: chunk * CHUNK,
                        centres,
                        rows: out,
                        scratch: (sum, mean_row),
                    })
                },
            );
        Ok(embeddings)
    }

    /// The channel count C, after checking that the maps chain: `3 → … → C`, then eq. 5.4's
    /// `C → C` maps.
    fn channels(&self) -> Result<usize> {
        let mut width = 3;
        for (l, layer) in self.layers.iter().enumerate() {
            if layer.input != width {
                return Err(Error::Invalid {
                    what: format!("projector layer {l}"),
                    reason: format!("takes {} channels, gets {width}", layer.input),
                });
            }
            width = layer.output;
        }
        let c = width;
        let (centre, neighbour) = (&self.centre, &self.neighbour);
        if c == 0
            || [
                centre.input,
                centre.output,
                neighbour.input,
                neighbour.output,
            ] != [c; 4]
        {
            return Err(Error::Invalid {
                what: "projector GNN".into(),
                reason: format!(
                    "fused inference needs {c}→{c} maps after {c}-channel layers, got {}→{} and {}→{}",
                    centre.input, centre.output, neighbour.input, neighbour.output
                ),
            });
        }
        Ok(c)
    }
}

/// The point-wise layers (then ReLU) on a chunk of points: `rows: #chunk × channels` written
/// from `points`, [`ROW_GROUP`] points at a time, with two scratch blocks of as many rows.
struct PointwiseRows<'a> {
    layers: &'a [HostAffine],
    channels: usize,
    points: &'a [[f32; 3]],
    rows: &'a mut [f32],
    scratch: (&'a mut Vec<f32>, &'a mut Vec<f32>),
}

impl pulp::WithSimd for PointwiseRows<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        let (a, b) = self.scratch;
        let c = self.channels.max(1);
        for (rows, points) in self
            .rows
            .chunks_mut(ROW_GROUP * c)
            .zip(self.points.chunks(ROW_GROUP))
        {
            let mut width = 3;
            a[..3 * points.len()].copy_from_slice(points.as_flattened());
            for layer in self.layers {
                let y = &mut b[..points.len() * layer.output];
                layer.apply_strided(a, width, y);
                for v in y.iter_mut() {
                    *v = v.max(0.0);
                }
                width = layer.output;
                std::mem::swap(a, b);
            }
            rows.copy_from_slice(&a[..rows.len()]);
        }
    }
}

/// Eq. 5.4 on a chunk of rows: row `r` of `rows` gets `ReLU(W_c f + b + W_n mean)`, where
/// `f` is row `centres[r]` of `features` and `mean` is row `first_row + r` of `mean_operator`
/// applied to `features`, summed in `f64` in column order as [`CsrMatrix::mul_dense`] sums;
/// two scratch rows.
struct GnnRows<'a> {
    projector: &'a FusedProjector,
    channels: usize,
    features: &'a [f32],
    mean_operator: &'a CsrMatrix,
    first_row: usize,
    centres: &'a [u32],
    rows: &'a mut [f32],
    scratch: (&'a mut Vec<f64>, &'a mut Vec<f32>),
}

impl pulp::WithSimd for GnnRows<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        let c = self.channels.max(1);
        let (sum, mean) = self.scratch;
        for (r, (row, &centre)) in self.rows.chunks_exact_mut(c).zip(self.centres).enumerate() {
            sum.fill(0.0);
            let (cols, vals) = self.mean_operator.row(self.first_row + r);
            for (&j, &v) in cols.iter().zip(vals) {
                let start = j as usize * c;
                let v = f64::from(v);
                for (a, &x) in sum.iter_mut().zip(&self.features[start..start + c]) {
                    *a += v * f64::from(x);
                }
            }
            for (m, &a) in mean.iter_mut().zip(sum.iter()) {
                *m = a as f32;
            }
            let start = centre as usize * c;
            self.projector
                .centre
                .apply(&self.features[start..start + c], row);
            self.projector.neighbour.accumulate(mean, row);
            for v in row.iter_mut() {
                *v = v.max(0.0);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::point_simplifier::{NeighbourIndex, PointSimplifier};
    use candle_core::{DType, Device};
    use meshgnn_graph::knn_graph;
    use rand::{Rng, SeedableRng, rngs::StdRng};

    #[test]
    fn packed_affine_equals_dense_product() {
        // W (3×2) = [[1, 2], [3, 4], [5, 6]]ᵀ stored transposed (2, 3); b = (1, -1, 0.5)
        let dev = Device::Cpu;
        let wt = Tensor::new(&[[1.0f32, 3.0, 5.0], [2.0, 4.0, 6.0]], &dev).unwrap();
        let b = Tensor::new(&[1.0f32, -1.0, 0.5], &dev).unwrap();
        let affine = HostAffine::from_transposed(&wt, Some(&b)).unwrap();
        let mut y = [0.0f32; 3];
        affine.apply(&[2.0, -1.0], &mut y);
        // (1·2 − 2 + 1, 3·2 − 4 − 1, 5·2 − 6 + 0.5)
        assert_eq!(y, [1.0, 1.0, 4.5]);
        affine.accumulate(&[1.0, 0.0], &mut y);
        assert_eq!(y, [2.0, 4.0, 9.5]);
    }

    #[test]
    fn grouped_tiles_and_rows_sum_as_one_row_at_a_time_in_input_order() {
        // widths that leave partial tiles and partial groups: 70 = 4 tiles + 6, 3 < one tile
        let dev = Device::Cpu;
        let mut rng = StdRng::seed_from_u64(4);
        for (input, output) in [(67, 70), (32, 3), (64, 16), (5, 33)] {
            let values: Vec<f32> = (0..input * output)
                .map(|_| rng.random_range(-1.0f32..1.0))
                .collect();
            let bias: Vec<f32> = (0..output).map(|_| rng.random_range(-1.0..1.0)).collect();
            let wt = Tensor::from_vec(values.clone(), (input, output), &dev).unwrap();
            let b = Tensor::from_vec(bias.clone(), output, &dev).unwrap();
            let affine = HostAffine::from_transposed(&wt, Some(&b)).unwrap();
            // each output: Σ_i x_i w_io from 0 in input order, then added to the bias
            let reference = |x: &[f32]| -> Vec<f32> {
                (0..output)
                    .map(|o| {
                        let acc = (0..input).fold(0.0f32, |a, i| a + x[i] * values[i * output + o]);
                        bias[o] + acc
                    })
                    .collect()
            };
            let stride = input + 2;
            for rows in 1..=9 {
                let xs: Vec<f32> = (0..rows * stride)
                    .map(|_| rng.random_range(-2.0f32..2.0))
                    .collect();
                let mut ys = vec![f32::NAN; rows * output];
                affine.apply_strided(&xs, stride, &mut ys);
                for (r, y) in ys.chunks_exact(output).enumerate() {
                    let x = &xs[r * stride..r * stride + input];
                    assert_eq!(y, reference(x), "{input}→{output}, row {r} of {rows}");
                    let mut one = vec![f32::NAN; output];
                    affine.apply(x, &mut one);
                    assert_eq!(one, y);
                }
            }
        }
    }

    #[test]
    fn fused_projector_equals_candle_projector_on_bundled_weights() {
        let model = crate::pretrained::load::<PointSimplifier>("point_simplifier").unwrap();
        let mut rng = StdRng::seed_from_u64(3);
        let points: Vec<[f32; 3]> = (0..5000)
            .map(|_| std::array::from_fn(|_| rng.random_range(-1.0f32..1.0)))
            .collect();
        let graph =
            NeighbourIndex::from_knn(&knn_graph(&points, 7).unwrap(), &Device::Cpu).unwrap();
        let fused = model
            .fused_projector(false)
            .unwrap()
            .expect("plain weights on the CPU take the fused path");
        let features = fused.pointwise(&points).unwrap();
        let all: Vec<u32> = (0..points.len() as u32).collect();
        let got = fused
            .aggregate(&features, graph.mean_matrix().unwrap(), &all)
            .unwrap();
        let input =
            Tensor::from_slice(points.as_flattened(), (points.len(), 3), &Device::Cpu).unwrap();
        let want: Vec<f32> = model
            .project(&input, &graph, false)
            .unwrap()
            .to_dtype(DType::F32)
            .unwrap()
            .flatten_all()
            .unwrap()
            .to_vec1()
            .unwrap();
        assert_eq!(got.len(), want.len());
        let scale = want.iter().fold(0.0f32, |m, v| m.max(v.abs()));
        assert!(scale > 0.0);
        for (i, (a, b)) in got.iter().zip(&want).enumerate() {
            assert!((a - b).abs() <= 1e-5 * scale.max(1.0), "{i}: {a} vs {b}");
        }
        // training mode and trainable weights keep the candle path
        assert!(model.fused_projector(true).unwrap().is_none());
        let map = candle_nn::VarMap::new();
        let vb = candle_nn::VarBuilder::from_varmap(&map, DType::F32, &Device::Cpu);
        let trainable = PointSimplifier::new(vb, &Default::default()).unwrap();
        assert!(trainable.fused_projector(false).unwrap().is_none());
    }

    #[test]
    fn rows_asked_alone_equal_the_same_rows_of_all() {
        // the lazy k-NN graph's rows and the aggregation of a subset: bit for bit the rows of
        // the full computation
        let model = crate::pretrained::load::<PointSimplifier>("point_simplifier").unwrap();
        let fused = model.fused_projector(false).unwrap().unwrap();
        let mut rng = StdRng::seed_from_u64(8);
        let points: Vec<[f32; 3]> = (0..3000)
            .map(|_| std::array::from_fn(|_| rng.random_range(-1.0f32..1.0)))
            .collect();
        let index = meshgnn_geometry::SpatialIndex::new(&points).unwrap();
        let lazy = NeighbourIndex::from_knn_index(index, 7, &Device::Cpu).unwrap();
        let rows: Vec<u32> = (0..3000).filter(|i| i % 5 != 2).rev().collect();
        let some_mean = lazy.mean_rows(&rows).unwrap();
        let features = fused.pointwise(&points).unwrap();
        let some = fused.aggregate(&features, &some_mean, &rows).unwrap();
        let full_graph =
            NeighbourIndex::from_knn(&knn_graph(&points, 7).unwrap(), &Device::Cpu).unwrap();
        let all: Vec<u32> = (0..3000).collect();
        let full = fused
            .aggregate(&features, full_graph.mean_matrix().unwrap(), &all)
            .unwrap();
        for (r, &i) in rows.iter().enumerate() {
            assert_eq!(
                some[r * 64..(r + 1) * 64],
                full[i as usize * 64..(i as usize + 1) * 64]
            );
        }
        // once every row was read, the lazy graph answers from its full slots: the same rows
        assert_eq!(
            lazy.mean_matrix().unwrap(),
            full_graph.mean_matrix().unwrap()
        );
        assert_eq!(lazy.mean_rows(&rows).unwrap(), some_mean);
    }

    #[test]
    fn fused_projector_rejects_a_graph_over_other_points() {
        let model = crate::pretrained::load::<PointSimplifier>("point_simplifier").unwrap();
        let fused = model.fused_projector(false).unwrap().unwrap();
        let graph = NeighbourIndex::from_rows(&[vec![1], vec![0]], &Device::Cpu).unwrap();
        let features = fused.pointwise(&[[0.0; 3]; 3]).unwrap();
        let mean = graph.mean_matrix().unwrap();
        assert!(fused.aggregate(&features, mean, &[0, 1]).is_err());
        assert!(fused.aggregate(&features[..128], mean, &[0, 2]).is_err());
    }
}
