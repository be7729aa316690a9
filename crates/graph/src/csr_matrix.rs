//! [`CsrMatrix`]: compressed sparse row matrices with `f32` values, the storage of every sparse
//! operator in meshgnn: adjacency `A` (thesis eq. 6.3-6.4, `A_s = SᵀAS`), pooling `D` and
//! unpooling `U` (COMA, Ranjan et al. 2018, ECCV; thesis ch. 3.3.4), applied as sparse × dense
//! products on row-major feature slices.
//!
//! # Conventions
//! - Indices are `u32` (column indices) and `usize` (row offsets); within a row, columns are
//!   strictly increasing (duplicates are summed at construction).
//! - Dense operands are row-major slices: `(rows × C)` is `rows·C` values, row `i` at
//!   `[i·C, (i+1)·C)`; this is the layout of a contiguous candle tensor `(rows, C)`.
//! - Products accumulate each output entry in `f64`, so results are independent of the thread
//!   count and of the order of the sparse entries.
//!
//! # The one conversion boundary
//! Geometry's spectral operators (graph and cotangent Laplacians, thesis eq. 2.13-2.14) are
//! `f64` `faer::sparse::SparseColMat`s, the form faer's sparse Cholesky/LU in the Laplacian
//! eigen-solver consumes; everything applied to features is a `CsrMatrix`. The crossing from
//! one to the other is [`CsrMatrix::from_faer`] and nowhere else (docs/architecture.md,
//! "Sparse matrices").

use meshgnn_geometry::faer::sparse::SparseColMat;
use rayon::prelude::*;

use crate::{Error, Result};

/// A `rows × cols` sparse matrix in CSR form with `f32` values.
///
/// ```
/// use meshgnn_graph::CsrMatrix;
/// let m = CsrMatrix::from_triplets(2, 3, &[(0, 2, 1.0), (1, 0, 2.0), (0, 2, 0.5)])?;
/// assert_eq!(m.row_offsets(), &[0, 1, 2]);
/// assert_eq!(m.col_indices(), &[2, 0]);
/// assert_eq!(m.values(), &[1.5, 2.0]);
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CsrMatrix {
    rows: usize,
    cols: usize,
    row_offsets: Vec<usize>,
    col_indices: Vec<u32>,
    values: Vec<f32>,
}

impl CsrMatrix {
    /// Builds a matrix from `(row, col, value)` triplets in any order; duplicates are summed
    /// (in `f64`, then rounded once), columns sorted within each row. O(nnz log nnz).
    ///
    /// Errors when a row or column index is out of range, a value is not finite, or `cols`
    /// does not fit in `u32`.
    ///
    /// ```
    /// use meshgnn_graph::CsrMatrix;
    /// let m = CsrMatrix::from_triplets(2, 2, &[(1, 1, 3.0), (0, 0, 1.0), (1, 1, -1.0)])?;
    /// assert_eq!(m.get(1, 1), 2.0);
    /// assert_eq!(m.nnz(), 2);
    /// assert!(CsrMatrix::from_triplets(2, 2, &[(2, 0, 1.0)]).is_err());
    /// # Ok::<(), meshgnn_graph::Error>(())
    /// ```
    pub fn from_triplets(rows: usize, cols: usize, triplets: &[(u32, u32, f32)]) -> Result<Self> {
        if u32::try_from(cols).is_err() {
            return Err(Error::InvalidParameter {
                name: "cols",
                message: format!("{cols} columns do not fit u32 column indices"),
            });
        }
        for (t, &(r, c, v)) in triplets.iter().enumerate() {
            if r as usize >= rows {
                return Err(Error::IndexOutOfRange {
                    what: "row of a triplet",
                    index: r as usize,
                    len: rows,
                });
            }
            if c as usize >= cols {
                return Err(Error::IndexOutOfRange {
                    what: "column of a triplet",
                    index: c as usize,
                    len: cols,
                });
            }
            if !v.is_finite() {
                return Err(Error::NonFinite {
                    what: "triplet value",
                    index: t,
                });
            }
        }
        let mut sorted: Vec<(u32, u32, f32)> = triplets.to_vec();
        // (row, col) first; the value breaks ties so the summation order is deterministic.
        sorted.par_sort_unstable_by(|a, b| (a.0, a.1).cmp(&(b.0, b.1)).then(a.2.total_cmp(&b.2)));
        let mut row_offsets = vec![0usize; rows + 1];
        let mut col_indices = Vec::with_capacity(sorted.len());
        let mut values = Vec::with_capacity(sorted.len());
        let mut i = 0;
        while i < sorted.len() {
            let (r, c, _) = sorted[i];
            let mut sum = 0.0f64;
            while i < sorted.len() && sorted[i].0 == r && sorted[i].1 == c {
                sum += f64::from(sorted[i].2);
                i += 1;
            }
            col_indices.push(c);
            values.push(sum as f32);
            row_offsets[r as usize + 1] += 1;
        }
        for r in 0..rows {
            row_offsets[r + 1] += row_offsets[r];
        }
        Ok(Self {
            rows,
            cols,
            row_offsets,
            col_indices,
            values,
        })
    }

    /// Wraps existing CSR arrays (e.g. from a candle tensor or a file), validating them:
    /// `row_offsets: rows + 1` non-decreasing from 0 to `nnz`, `col_indices: nnz` strictly
    /// increasing within each row and `< cols`, `values: nnz` finite.
    ///
    /// ```
    /// use meshgnn_graph::CsrMatrix;
    /// let m = CsrMatrix::from_parts(2, 2, vec![0, 1, 2], vec![1, 0], vec![1.0, 1.0])?;
    /// assert_eq!(m.get(0, 1), 1.0);
    /// assert!(CsrMatrix::from_parts(2, 2, vec![0, 2, 2], vec![1, 0], vec![1.0, 1.0]).is_err());
    /// # Ok::<(), meshgnn_graph::Error>(())
    /// ```
    pub fn from_parts(
        rows: usize,
        cols: usize,
        row_offsets: Vec<usize>,
        col_indices: Vec<u32>,
        values: Vec<f32>,
    ) -> Result<Self> {
        if row_offsets.len() != rows + 1 {
            return Err(Error::ShapeMismatch {
                what: "length of row_offsets (rows + 1)",
                expected: rows + 1,
                actual: row_offsets.len(),
            });
        }
        if values.len() != col_indices.len() {
            return Err(Error::ShapeMismatch {
                what: "length of values (nnz)",
                expected: col_indices.len(),
                actual: values.len(),
            });
        }
        if row_offsets.first() != Some(&0) || row_offsets.last() != Some(&col_indices.len()) {
            return Err(Error::InvalidParameter {
                name: "row_offsets",
                message: format!("must start at 0 and end at nnz = {}", col_indices.len()),
            });
        }
        for r in 0..rows {
            let (s, e) = (row_offsets[r], row_offsets[r + 1]);
            let row = col_indices
                .get(s..e)
                .ok_or_else(|| Error::InvalidParameter {
                    name: "row_offsets",
                    message: format!("row {r} has decreasing offsets {s}..{e}"),
                })?;
            if let Some(&c) = row.iter().find(|&&c| c as usize >= cols) {
                return Err(Error::IndexOutOfRange {
                    what: "column index",
                    index: c as usize,
                    len: cols,
                });
            }
            if row.windows(2).any(|w| w[0] >= w[1]) {
                return Err(Error::InvalidParameter {
                    name: "col_indices",
                    message: format!("columns of row {r} are not strictly increasing"),
                });
            }
        }
        if let Some(index) = values.iter().position(|v| !v.is_finite()) {
            return Err(Error::NonFinite {
                what: "value",
                index,
            });
        }
        Ok(Self {
            rows,
            cols,
            row_offsets,
            col_indices,
            values,
        })
    }

    /// A geometry operator (`f64`, compressed sparse column, e.g. a Laplacian of
    /// `meshgnn_geometry`) as a `CsrMatrix`, each value rounded once to `f32`: the one
    /// conversion between the two sparse types (module docs). O(nnz log nnz).
    ///
    /// Errors when a value is not finite or overflows `f32`, or a dimension does not fit `u32`.
    ///
    /// ```
    /// use meshgnn_geometry::combinatorial_laplacian;
    /// use meshgnn_graph::CsrMatrix;
    /// let l = CsrMatrix::from_faer(&combinatorial_laplacian(3, &[[0, 1], [1, 2]])?)?;
    /// assert_eq!((l.get(1, 1), l.get(0, 1), l.get(0, 2)), (2.0, -1.0, 0.0));
    /// assert_eq!(l.mul_dense(&[1.0; 3], 1)?, vec![0.0; 3]); // L·1 = 0
    /// # Ok::<(), meshgnn_graph::Error>(())
    /// ```
    pub fn from_faer(matrix: &SparseColMat<usize, f64>) -> Result<Self> {
        let (rows, cols) = (matrix.nrows(), matrix.ncols());
        if u32::try_from(rows).is_err() {
            return Err(Error::InvalidParameter {
                name: "rows",
                message: format!("{rows} rows do not fit u32 row indices"),
            });
        }
        // In range: both dimensions fit u32 (rows above, cols in `from_triplets`).
        let triplets: Vec<(u32, u32, f32)> = matrix
            .as_ref()
            .triplet_iter()
            .map(|t| (t.row as u32, t.col as u32, *t.val as f32))
            .collect();
        Self::from_triplets(rows, cols, &triplets)
    }

    /// The `n × n` identity.
    ///
    /// ```
    /// let i = meshgnn_graph::CsrMatrix::identity(3);
    /// assert_eq!((i.nnz(), i.get(2, 2), i.get(0, 1)), (3, 1.0, 0.0));
    /// ```
    pub fn identity(n: usize) -> Self {
        Self {
            rows: n,
            cols: n,
            row_offsets: (0..=n).collect(),
            col_indices: (0..n as u32).collect(),
            values: vec![1.0; n],
        }
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Number of columns.
    pub fn cols(&self) -> usize {
        self.cols
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.values.len()
    }

    /// Row offsets, `rows + 1` entries: row `i` is `[offsets[i], offsets[i+1])`.
    pub fn row_offsets(&self) -> &[usize] {
        &self.row_offsets
    }

    /// Column index of every stored entry, `nnz`, increasing within a row.
    pub fn col_indices(&self) -> &[u32] {
        &self.col_indices
    }

    /// Value of every stored entry, `nnz`.
    pub fn values(&self) -> &[f32] {
        &self.values
    }

    /// The stored columns and values of row `i` (empty when `i >= rows`).
    pub fn row(&self, i: usize) -> (&[u32], &[f32]) {
        match (self.row_offsets.get(i), self.row_offsets.get(i + 1)) {
            (Some(&s), Some(&e)) => (
                self.col_indices.get(s..e).unwrap_or(&[]),
                self.values.get(s..e).unwrap_or(&[]),
            ),
            _ => (&[], &[]),
        }
    }

    /// The stored columns of every row without the diagonal: a square adjacency matrix as
    /// neighbour lists (what the graph layers gather over). Errors when it is not square.
    ///
    /// ```
    /// use meshgnn_graph::CsrMatrix;
    /// let a = CsrMatrix::from_triplets(2, 2, &[(0, 0, 1.0), (0, 1, 1.0), (1, 0, 1.0)])?;
    /// assert_eq!(a.off_diagonal_rows()?, vec![vec![1], vec![0]]);
    /// assert!(CsrMatrix::from_triplets(2, 3, &[])?.off_diagonal_rows().is_err());
    /// # Ok::<(), meshgnn_graph::Error>(())
    /// ```
    pub fn off_diagonal_rows(&self) -> Result<Vec<Vec<u32>>> {
        if self.cols != self.rows {
            return Err(Error::ShapeMismatch {
                what: "columns of the adjacency (must be square)",
                expected: self.rows,
                actual: self.cols,
            });
        }
        Ok((0..self.rows)
            .map(|i| {
                let (columns, _) = self.row(i);
                columns
                    .iter()
                    .copied()
                    .filter(|&j| j as usize != i)
                    .collect()
            })
            .collect())
    }

    /// Entry `(i, j)`, zero when not stored or out of range. O(log row length).
    pub fn get(&self, i: usize, j: usize) -> f32 {
        let (cols, vals) = self.row(i);
        u32::try_from(j)
            .ok()
            .and_then(|j| cols.binary_search(&j).ok())
            .and_then(|p| vals.get(p).copied())
            .unwrap_or(0.0)
    }

    /// The `(row, col, value)` triplets in row-major order.
    pub fn to_triplets(&self) -> Vec<(u32, u32, f32)> {
        (0..self.rows)
            .flat_map(|r| {
                let (cols, vals) = self.row(r);
                cols.iter().zip(vals).map(move |(&c, &v)| (r as u32, c, v))
            })
            .collect()
    }

    /// The transpose `cols × rows`, by a counting sort: O(nnz + rows + cols).
    ///
    /// ```
    /// use meshgnn_graph::CsrMatrix;
    /// let m = CsrMatrix::from_triplets(2, 3, &[(0, 2, 1.0), (1, 0, 2.0)])?;
    /// let t = m.transpose();
    /// assert_eq!((t.rows(), t.cols(), t.get(2, 0), t.get(0, 1)), (3, 2, 1.0, 2.0));
    /// # Ok::<(), meshgnn_graph::Error>(())
    /// ```
    pub fn transpose(&self) -> Self {
        let mut row_offsets = vec![0usize; self.cols + 1];
        for &c in &self.col_indices {
            row_offsets[c as usize + 1] += 1;
        }
        for c in 0..self.cols {
            row_offsets[c + 1] += row_offsets[c];
        }
        let mut next = row_offsets.clone();
        let mut col_indices = vec![0u32; self.nnz()];
        let mut values = vec![0.0f32; self.nnz()];
        // Rows visited in increasing order, so columns of the transpose come out sorted.
        for r in 0..self.rows {
            let (cols, vals) = self.row(r);
            for (&c, &v) in cols.iter().zip(vals) {
                let slot = next[c as usize];
                next[c as usize] += 1;
                col_indices[slot] = r as u32;
                values[slot] = v;
            }
        }
        Self {
            rows: self.cols,
            cols: self.rows,
            row_offsets,
            col_indices,
            values,
        }
    }

    /// The sum of each row, `rows` (in `f64`, rounded once): the degree vector of an
    /// adjacency matrix.
    ///
    /// ```
    /// use meshgnn_graph::CsrMatrix;
    /// let m = CsrMatrix::from_triplets(2, 2, &[(0, 0, 1.0), (0, 1, 2.5)])?;
    /// assert_eq!(m.row_sums(), vec![3.5, 0.0]);
    /// # Ok::<(), meshgnn_graph::Error>(())
    /// ```
    pub fn row_sums(&self) -> Vec<f32> {
        (0..self.rows)
            .into_par_iter()
            .map(|r| self.row(r).1.iter().map(|&v| f64::from(v)).sum::<f64>() as f32)
            .collect()
    }

    /// Sparse × dense: `self (rows × cols) · dense (cols × channels)`, both dense slices
    /// row-major, giving `rows × channels`. Rayon-parallel over output rows; each entry is
    /// accumulated in `f64`. Applies pooling `D·X` and unpooling `U·X` (thesis ch. 3.3.4).
    ///
    /// ```
    /// use meshgnn_graph::CsrMatrix;
    /// let m = CsrMatrix::from_triplets(1, 2, &[(0, 0, 2.0), (0, 1, 1.0)])?;
    /// assert_eq!(m.mul_dense(&[1.0, 10.0, 3.0, 30.0], 2)?, vec![5.0, 50.0]);
    /// # Ok::<(), meshgnn_graph::Error>(())
    /// ```
    pub fn mul_dense(&self, dense: &[f32], channels: usize) -> Result<Vec<f32>> {
        let mut out = vec![0.0f32; self.rows * channels];
        self.mul_dense_into(dense, channels, &mut out)?;
        Ok(out)
    }

    /// [`CsrMatrix::mul_dense`] into a caller-provided `out: rows × channels` (overwritten),
    /// for loops that reuse their buffers.
    pub fn mul_dense_into(&self, dense: &[f32], channels: usize, out: &mut [f32]) -> Result<()> {
        if dense.len() != self.cols * channels {
            return Err(Error::ShapeMismatch {
                what: "length of the dense operand (cols × channels)",
                expected: self.cols * channels,
                actual: dense.len(),
            });
        }
        if out.len() != self.rows * channels {
            return Err(Error::ShapeMismatch {
                what: "length of the output (rows × channels)",
                expected: self.rows * channels,
                actual: out.len(),
            });
        }
        if channels == 0 {
            return Ok(());
        }
        out.par_chunks_mut(channels).enumerate().for_each_init(
            || vec![0.0f64; channels],
            |acc, (r, out_row)| {
                acc.fill(0.0);
                let (cols, vals) = self.row(r);
                for (&c, &v) in cols.iter().zip(vals) {
                    let start = c as usize * channels;
                    // In range: c < cols was checked at construction and the length above.
                    if let Some(x) = dense.get(start..start + channels) {
                        let v = f64::from(v);
                        for (a, &x) in acc.iter_mut().zip(x) {
                            *a += v * f64::from(x);
                        }
                    }
                }
                for (o, &a) in out_row.iter_mut().zip(acc.iter()) {
                    *o = a as f32;
                }
            },
        );
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng, rngs::StdRng};

    fn random_triplets(
        rng: &mut StdRng,
        rows: usize,
        cols: usize,
        n: usize,
    ) -> Vec<(u32, u32, f32)> {
        (0..n)
            .map(|_| {
                (
                    rng.random_range(0..rows as u32),
                    rng.random_range(0..cols as u32),
                    rng.random_range(-1.0..1.0),
                )
            })
            .collect()
    }

    fn dense_of(rows: usize, cols: usize, t: &[(u32, u32, f32)]) -> Vec<f64> {
        let mut d = vec![0.0f64; rows * cols];
        for &(r, c, v) in t {
            d[r as usize * cols + c as usize] += f64::from(v);
        }
        d
    }

    #[test]
    fn product_matches_dense_reference() {
        let mut rng = StdRng::seed_from_u64(7);
        for &(rows, cols, nnz, ch) in &[(5, 7, 20, 3), (40, 13, 300, 8), (1, 1, 3, 1), (9, 4, 0, 2)]
        {
            let t = random_triplets(&mut rng, rows, cols, nnz);
            let m = CsrMatrix::from_triplets(rows, cols, &t).unwrap();
            let dense = dense_of(rows, cols, &t);
            let x: Vec<f32> = (0..cols * ch)
                .map(|_| rng.random_range(-2.0..2.0))
                .collect();
            let y = m.mul_dense(&x, ch).unwrap();
            for r in 0..rows {
                for c in 0..ch {
                    let want: f64 = (0..cols)
                        .map(|k| dense[r * cols + k] * f64::from(x[k * ch + c]))
                        .sum();
                    assert!((f64::from(y[r * ch + c]) - want).abs() < 1e-5, "{r},{c}");
                }
            }
            for r in 0..rows {
                for c in 0..cols {
                    assert!((f64::from(m.get(r, c)) - dense[r * cols + c]).abs() < 1e-6);
                }
            }
        }
    }

    #[test]
    fn columns_sorted_and_duplicates_summed() {
        let m =
            CsrMatrix::from_triplets(2, 4, &[(0, 3, 1.0), (0, 1, 2.0), (0, 3, 4.0), (1, 0, 1.0)])
                .unwrap();
        assert_eq!(m.row_offsets(), &[0, 2, 3]);
        assert_eq!(m.col_indices(), &[1, 3, 0]);
        assert_eq!(m.values(), &[2.0, 5.0, 1.0]);
    }

    #[test]
    fn transpose_twice_is_identity_and_matches_dense() {
        let mut rng = StdRng::seed_from_u64(3);
        let t = random_triplets(&mut rng, 17, 11, 80);
        let m = CsrMatrix::from_triplets(17, 11, &t).unwrap();
        let tt = m.transpose();
        for r in 0..17 {
            for c in 0..11 {
                assert_eq!(m.get(r, c), tt.get(c, r));
            }
        }
        for r in 0..11 {
            assert!(tt.row(r).0.windows(2).all(|w| w[0] < w[1]));
        }
        assert_eq!(tt.transpose(), m);
    }

    #[test]
    fn identity_product_and_row_sums() {
        let x: Vec<f32> = (0..12).map(|i| i as f32 * 0.5).collect();
        assert_eq!(CsrMatrix::identity(4).mul_dense(&x, 3).unwrap(), x);
        let m = CsrMatrix::from_triplets(3, 3, &[(0, 1, 1.0), (2, 0, 2.0), (2, 2, 3.0)]).unwrap();
        assert_eq!(m.row_sums(), vec![1.0, 0.0, 5.0]);
    }

    proptest::proptest! {
        #[test]
        fn transpose_is_an_involution_and_products_agree(
            triplets in proptest::collection::vec((0u32..9, 0u32..6, -4.0f32..4.0), 0..60),
            x in proptest::collection::vec(-3.0f32..3.0, 6 * 2),
        ) {
            let m = CsrMatrix::from_triplets(9, 6, &triplets).unwrap();
            proptest::prop_assert_eq!(&m.transpose().transpose(), &m);
            let dense = dense_of(9, 6, &triplets);
            let y = m.mul_dense(&x, 2).unwrap();
            for r in 0..9 {
                for c in 0..2 {
                    let want: f64 = (0..6).map(|k| dense[r * 6 + k] * f64::from(x[k * 2 + c])).sum();
                    proptest::prop_assert!((f64::from(y[r * 2 + c]) - want).abs() < 1e-4);
                }
            }
        }
    }

    #[test]
    fn from_faer_keeps_every_entry_of_a_cotangent_laplacian() {
        let sphere = meshgnn_geometry::icosphere(2);
        let l = meshgnn_geometry::cotangent_laplacian(&sphere).unwrap();
        let m = CsrMatrix::from_faer(&l).unwrap();
        assert_eq!(
            (m.rows(), m.cols(), m.nnz()),
            (l.nrows(), l.ncols(), l.as_ref().triplet_iter().count())
        );
        let dense = l.to_dense();
        for r in 0..m.rows() {
            for c in 0..m.cols() {
                assert_eq!(m.get(r, c), dense[(r, c)] as f32);
            }
        }
        // L·1 = 0 survives the rounding to f32 (up to it).
        let ones = vec![1.0f32; m.cols()];
        let scale = m.values().iter().fold(0.0f32, |a, v| a.max(v.abs()));
        assert!(
            m.mul_dense(&ones, 1)
                .unwrap()
                .iter()
                .all(|x| x.abs() < 1e-6 * scale)
        );
        let huge =
            meshgnn_geometry::faer::sparse::SparseColMat::<usize, f64>::try_new_from_triplets(
                1,
                1,
                &[meshgnn_geometry::faer::sparse::Triplet::new(0, 0, 1e300)],
            )
            .unwrap();
        assert!(matches!(
            CsrMatrix::from_faer(&huge),
            Err(Error::NonFinite { .. })
        ));
    }

    #[test]
    fn rejects_bad_input() {
        assert!(matches!(
            CsrMatrix::from_triplets(2, 2, &[(0, 2, 1.0)]),
            Err(Error::IndexOutOfRange { .. })
        ));
        assert!(matches!(
            CsrMatrix::from_triplets(2, 2, &[(0, 0, f32::NAN)]),
            Err(Error::NonFinite { .. })
        ));
        let m = CsrMatrix::identity(2);
        assert!(matches!(
            m.mul_dense(&[1.0; 5], 2),
            Err(Error::ShapeMismatch { .. })
        ));
    }
}
