//! A sparse Cholesky factor (faer, AMD fill-reducing ordering) — `A = L Lᵀ` of a positive
//! definite `A`, or `A = L D Lᵀ` without pivoting of an indefinite one — whose solves split the
//! right-hand sides into fixed-width column groups run in parallel, each group sequential.
//!
//! The `L D Lᵀ` form also counts the eigenvalues below zero: by Sylvester's law of inertia `A`
//! has as many negative eigenvalues as `D` has negative pivots. The eigen-solver's interior
//! shift uses that count to prove it found every eigenvalue below the shift.
//!
//! faer's own parallel solve synchronises inside every supernode; on a small machine whose
//! cores are shared that made the shift-invert eigen-solver 2-3× slower than one thread
//! (docs/geometry.md). Fixed groups keep the result independent of the thread count. A
//! simplicial factor (what faer picks for mesh Laplacians) is solved here, with a group's
//! right-hand sides interleaved row by row; a supernodal one by faer.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::SparseColMatRef;
use faer::sparse::linalg::cholesky::supernodal::SupernodalLdltRef;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LdltRef, LltRef, SymbolicCholesky, SymbolicCholeskyRaw,
    SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::{Conj, MatMut, Par, Side};
use rayon::prelude::*;

/// Right-hand sides solved together by one thread.
const COLUMNS_PER_TASK: usize = 12;

/// A pivot of `D` this much smaller in magnitude than the largest makes the `L D Lᵀ` factor
/// unusable: without pivoting, its solves would lose most of their digits.
const SMALLEST_PIVOT_RATIO: f64 = 1e-10;

/// The Cholesky factor of a symmetric sparse matrix, `L Lᵀ` or `L D Lᵀ`.
pub(crate) struct SparseCholesky {
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
    /// `Some(number of negative pivots)` for `L D Lᵀ`, `None` for `L Lᵀ`.
    negative_pivots: Option<usize>,
}

impl SparseCholesky {
    /// `L Lᵀ` of `matrix` (both triangles stored); fails with faer's message when it is not
    /// numerically positive definite.
    pub(crate) fn new(matrix: SparseColMatRef<'_, usize, f64>) -> Result<Self, String> {
        let symbolic = symbolic_factor(matrix)?;
        let mut values = vec![0.0; symbolic.len_val()];
        let mut scratch = MemBuffer::new(
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
        );
        symbolic
            .factorize_numeric_llt(
                &mut values,
                matrix,
                Side::Lower,
                Default::default(),
                Par::Seq,
                MemStack::new(&mut scratch),
                Default::default(),
            )
            .map_err(|e| format!("{e:?}"))?;
        Ok(Self {
            symbolic,
            values,
            negative_pivots: None,
        })
    }

    /// `L D Lᵀ` of the symmetric, possibly indefinite `matrix` (both triangles stored), without
    /// pivoting; fails when a pivot is zero or below `SMALLEST_PIVOT_RATIO` of the largest.
    pub(crate) fn new_indefinite(matrix: SparseColMatRef<'_, usize, f64>) -> Result<Self, String> {
        let symbolic = symbolic_factor(matrix)?;
        let mut values = vec![0.0; symbolic.len_val()];
        let mut scratch = MemBuffer::new(
            symbolic.factorize_numeric_ldlt_scratch::<f64>(Par::Seq, Default::default()),
        );
        symbolic
            .factorize_numeric_ldlt(
                &mut values,
                matrix,
                Side::Lower,
                Default::default(),
                Par::Seq,
                MemStack::new(&mut scratch),
                Default::default(),
            )
            .map_err(|e| format!("{e:?}"))?;
        let pivots = ldlt_pivots(&symbolic, &values);
        let largest = pivots.iter().fold(0.0f64, |m, d| m.max(d.abs()));
        if pivots
            .iter()
            .any(|d| d.is_nan() || d.abs() <= SMALLEST_PIVOT_RATIO * largest)
        {
            return Err("a pivot of L D Lᵀ is (nearly) zero".into());
        }
        let negative = pivots.iter().filter(|&&d| d < 0.0).count();
        Ok(Self {
            symbolic,
            values,
            negative_pivots: Some(negative),
        })
    }

    /// The number of negative eigenvalues of the matrix, known for an `L D Lᵀ` factor.
    pub(crate) fn negative_eigenvalues(&self) -> Option<usize> {
        self.negative_pivots
    }

    /// `rhs ← A⁻¹ rhs`.
    pub(crate) fn solve_in_place(&self, rhs: MatMut<'_, f64>) {
        let mut groups = Vec::new();
        let mut rest = rhs;
        while rest.ncols() > COLUMNS_PER_TASK {
            let (head, tail) = rest.split_at_col_mut(COLUMNS_PER_TASK);
            groups.push(head);
            rest = tail;
        }
        groups.push(rest);
        groups
            .into_par_iter()
            .for_each(|group| match self.symbolic.raw() {
                SymbolicCholeskyRaw::Simplicial(simplicial) => {
                    self.solve_simplicial(simplicial, group)
                }
                SymbolicCholeskyRaw::Supernodal(_) => self.solve_with_faer(group),
            });
    }

    /// `rhs ← A⁻¹ rhs` for at most `COLUMNS_PER_TASK` columns with a simplicial factor (faer
    /// picks one for mesh Laplacians of 45k vertices), the right-hand sides interleaved row
    /// by row: each entry of the factor is read once for all of them and updates one short
    /// contiguous run. faer's own solve reads the factor once per 4 columns and updates 4
    /// strided ones; the eigen-solver on a 45k-vertex scan took 1.27-1.35 s with this one
    /// against 1.34-1.42 s (4 interleaved runs, docs/geometry.md).
    fn solve_simplicial(
        &self,
        simplicial: &faer::sparse::linalg::cholesky::simplicial::SymbolicSimplicialCholesky<usize>,
        mut rhs: MatMut<'_, f64>,
    ) {
        let n = rhs.nrows();
        let width = rhs.ncols();
        let col_ptr = simplicial.col_ptr();
        let row_idx = simplicial.row_idx();
        let values = &self.values;
        // Row `p` of the permuted system is row `fwd[p]` of the matrix.
        let perm = self.symbolic.perm();
        let fwd = |p: usize| perm.map_or(p, |perm| perm.arrays().0[p]);
        let mut x = vec![[0.0f64; COLUMNS_PER_TASK]; n];
        for c in 0..width {
            let column = rhs.as_ref().col(c);
            for (p, row) in x.iter_mut().enumerate() {
                row[c] = column[fwd(p)];
            }
        }
        let unit_diagonal = self.negative_pivots.is_some();
        // L y = b, column by column; the first entry of each column is its diagonal (`D` for
        // `L D Lᵀ`, whose `L` has a unit diagonal).
        for j in 0..n {
            let (start, end) = (col_ptr[j], col_ptr[j + 1]);
            let mut xj = x[j];
            if !unit_diagonal {
                let d = values[start];
                for v in &mut xj {
                    *v /= d;
                }
                x[j] = xj;
            }
            for k in start + 1..end {
                let (i, l) = (row_idx[k], values[k]);
                let xi = &mut x[i];
                for c in 0..COLUMNS_PER_TASK {
                    xi[c] -= l * xj[c];
                }
            }
        }
        if unit_diagonal {
            for (j, xj) in x.iter_mut().enumerate() {
                let d = values[col_ptr[j]];
                for v in xj.iter_mut() {
                    *v /= d;
                }
            }
        }
        // Lᵀ x = y, backwards.
        for j in (0..n).rev() {
            let (start, end) = (col_ptr[j], col_ptr[j + 1]);
            let mut sum = x[j];
            for k in start + 1..end {
                let (i, l) = (row_idx[k], values[k]);
                let xi = &x[i];
                for c in 0..COLUMNS_PER_TASK {
                    sum[c] -= l * xi[c];
                }
            }
            if !unit_diagonal {
                let d = values[start];
                for v in &mut sum {
                    *v /= d;
                }
            }
            x[j] = sum;
        }
        for c in 0..width {
            let mut column = rhs.as_mut().col_mut(c);
            for (p, row) in x.iter().enumerate() {
                column[fwd(p)] = row[c];
            }
        }
    }

    /// `rhs ← A⁻¹ rhs` with faer's solve (supernodal factors).
    fn solve_with_faer(&self, group: MatMut<'_, f64>) {
        let mut scratch = MemBuffer::new(
            self.symbolic
                .solve_in_place_scratch::<f64>(group.ncols(), Par::Seq),
        );
        let stack = MemStack::new(&mut scratch);
        match self.negative_pivots {
            None => LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
                Conj::No,
                group,
                Par::Seq,
                stack,
            ),
            Some(_) => LdltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
                Conj::No,
                group,
                Par::Seq,
                stack,
            ),
        }
    }
}

/// The symbolic factor of `matrix`'s pattern with the AMD ordering.
fn symbolic_factor(
    matrix: SparseColMatRef<'_, usize, f64>,
) -> Result<SymbolicCholesky<usize>, String> {
    factorize_symbolic_cholesky(
        matrix.symbolic(),
        Side::Lower,
        SymmetricOrdering::Amd,
        CholeskySymbolicParams::default(),
    )
    .map_err(|e| format!("{e:?}"))
}

/// The diagonal `D` of an `L D Lᵀ` factor (faer stores it on the diagonal of `L`: the first
/// entry of each simplicial column, the diagonal of each supernode's leading block).
fn ldlt_pivots(symbolic: &SymbolicCholesky<usize>, values: &[f64]) -> Vec<f64> {
    match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(simplicial) => {
            let col_ptr = simplicial.col_ptr();
            (0..simplicial.ncols())
                .map(|j| values[col_ptr[j]])
                .collect()
        }
        SymbolicCholeskyRaw::Supernodal(supernodal) => {
            let factor = SupernodalLdltRef::new(supernodal, values);
            (0..supernodal.n_supernodes())
                .flat_map(|s| {
                    let block = factor.supernode(s).val();
                    (0..block.ncols()).map(move |i| block[(i, i)])
                })
                .collect()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::Mat;
    use faer::linalg::solvers::Solve;
    use faer::sparse::{SparseColMat, Triplet};

    #[test]
    fn solves_a_path_laplacian_like_faer_for_any_thread_count() {
        // Tridiagonal 2.5 on the diagonal, -1 beside it: positive definite.
        let n = 500;
        let mut entries = Vec::new();
        for i in 0..n {
            entries.push(Triplet::new(i, i, 2.5));
            if i + 1 < n {
                entries.push(Triplet::new(i, i + 1, -1.0));
                entries.push(Triplet::new(i + 1, i, -1.0));
            }
        }
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &entries).unwrap();
        let rhs = Mat::<f64>::from_fn(n, 2 * COLUMNS_PER_TASK + 1, |i, j| {
            (i * 7 + j * 3) as f64 % 11.0
        });
        let factor = SparseCholesky::new(a.as_ref()).unwrap();
        assert!(matches!(
            factor.symbolic.raw(),
            SymbolicCholeskyRaw::Simplicial(_)
        ));
        let mut x = rhs.clone();
        factor.solve_in_place(x.as_mut());
        assert!((&a * &x - &rhs).norm_max() < 1e-10);
        let expected = a.sp_cholesky(Side::Lower).unwrap().solve(&rhs);
        assert!((&x - &expected).norm_max() < 1e-12);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let mut alone = rhs.clone();
        pool.install(|| factor.solve_in_place(alone.as_mut()));
        assert_eq!(x, alone);
    }

    #[test]
    fn an_indefinite_matrix_is_an_error() {
        let entries = [Triplet::new(0, 0, 1.0), Triplet::new(1, 1, -1.0)];
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(2, 2, &entries).unwrap();
        assert!(SparseCholesky::new(a.as_ref()).is_err());
    }

    /// The 5-point Laplacian of a `side × side` grid (Dirichlet), shifted by `shift`: its
    /// eigenvalues are `4 − 2cos(aπ/(side+1)) − 2cos(bπ/(side+1)) − shift`.
    fn shifted_grid(side: usize, shift: f64) -> (SparseColMat<usize, f64>, usize) {
        let index = |i: usize, j: usize| i * side + j;
        let mut entries = Vec::new();
        for i in 0..side {
            for j in 0..side {
                entries.push(Triplet::new(index(i, j), index(i, j), 4.0 - shift));
                for (di, dj) in [(1, 0), (0, 1)] {
                    if i + di < side && j + dj < side {
                        entries.push(Triplet::new(index(i, j), index(i + di, j + dj), -1.0));
                        entries.push(Triplet::new(index(i + di, j + dj), index(i, j), -1.0));
                    }
                }
            }
        }
        let n = side * side;
        let matrix = SparseColMat::try_new_from_triplets(n, n, &entries).unwrap();
        let theta =
            |a: usize| 2.0 - 2.0 * (a as f64 * std::f64::consts::PI / (side + 1) as f64).cos();
        let negative = (1..=side)
            .flat_map(|a| (1..=side).map(move |b| (a, b)))
            .filter(|&(a, b)| theta(a) + theta(b) < shift)
            .count();
        (matrix, negative)
    }

    /// The path Laplacian on `n` vertices (Dirichlet) shifted by `shift`, and its number of
    /// negative eigenvalues (`2 − 2cos(kπ/(n+1)) − shift`).
    fn shifted_path(n: usize, shift: f64) -> (SparseColMat<usize, f64>, usize) {
        let mut entries = Vec::new();
        for i in 0..n {
            entries.push(Triplet::new(i, i, 2.0 - shift));
            if i + 1 < n {
                entries.push(Triplet::new(i, i + 1, -1.0));
                entries.push(Triplet::new(i + 1, i, -1.0));
            }
        }
        let negative = (1..=n)
            .filter(|&k| {
                2.0 - 2.0 * (k as f64 * std::f64::consts::PI / (n + 1) as f64).cos() < shift
            })
            .count();
        (
            SparseColMat::try_new_from_triplets(n, n, &entries).unwrap(),
            negative,
        )
    }

    #[test]
    fn indefinite_factor_counts_the_negative_eigenvalues_and_solves() {
        // A path and 40 × 40 grids (simplicial factors) and a 150 × 150 grid (supernodal),
        // shifted inside their spectra.
        let cases = [
            shifted_path(300, 1.1),
            shifted_grid(40, 1.3),
            shifted_grid(40, 4.07),
            shifted_grid(40, 7.5),
            shifted_grid(150, 2.1),
        ];
        for (case, (matrix, expected)) in cases.into_iter().enumerate() {
            let factor = SparseCholesky::new_indefinite(matrix.as_ref()).unwrap();
            let simplicial = matches!(factor.symbolic.raw(), SymbolicCholeskyRaw::Simplicial(_));
            assert_eq!(simplicial, case < 4, "case {case}");
            assert_eq!(factor.negative_eigenvalues(), Some(expected));
            assert!(expected > 0);
            let rhs = Mat::<f64>::from_fn(matrix.nrows(), 2 * COLUMNS_PER_TASK + 1, |i, j| {
                ((i * 7 + j * 3) % 11) as f64 - 5.0
            });
            let mut x = rhs.clone();
            factor.solve_in_place(x.as_mut());
            let residual = (&matrix * &x - &rhs).norm_max() / rhs.norm_max();
            assert!(residual < 1e-9, "residual {residual}");
        }
        // Positive definite input: no negative pivots, and `L Lᵀ` reports no count.
        let (matrix, _) = shifted_grid(10, -0.5);
        let factor = SparseCholesky::new_indefinite(matrix.as_ref()).unwrap();
        assert_eq!(factor.negative_eigenvalues(), Some(0));
        assert_eq!(
            SparseCholesky::new(matrix.as_ref())
                .unwrap()
                .negative_eigenvalues(),
            None
        );
    }

    #[test]
    fn a_shift_on_an_eigenvalue_is_an_error() {
        // side 3: a = b = 2 gives 4 − 0 − 0 = 4, an eigenvalue; the shifted matrix is singular.
        let (matrix, _) = shifted_grid(3, 4.0);
        assert!(SparseCholesky::new_indefinite(matrix.as_ref()).is_err());
    }
}
