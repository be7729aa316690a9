//! A sparse Cholesky factor `A = L Lᵀ` (faer, AMD fill-reducing ordering) whose solves split the
//! right-hand sides into fixed-width column groups run in parallel, each group sequential.
//!
//! faer's own parallel solve synchronises inside every supernode; on a small machine whose
//! cores are shared that made the shift-invert eigen-solver 2-3× slower than one thread
//! (docs/geometry.md). Fixed groups keep the result independent of the thread count.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::SparseColMatRef;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::{Conj, MatMut, Par, Side};
use rayon::prelude::*;

/// Right-hand sides solved together by one thread.
const COLUMNS_PER_TASK: usize = 12;

/// The Cholesky factor of a symmetric positive definite sparse matrix.
pub(crate) struct SparseCholesky {
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
}

impl SparseCholesky {
    /// Factorises `matrix` (both triangles stored); fails with faer's message when it is not
    /// numerically positive definite.
    pub(crate) fn new(matrix: SparseColMatRef<'_, usize, f64>) -> Result<Self, String> {
        let symbolic = factorize_symbolic_cholesky(
            matrix.symbolic(),
            Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .map_err(|e| format!("{e:?}"))?;
        let mut values = vec![0.0; symbolic.len_val()];
        let par = Par::Seq;
        let mut scratch =
            MemBuffer::new(symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()));
        symbolic
            .factorize_numeric_llt(
                &mut values,
                matrix,
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut scratch),
                Default::default(),
            )
            .map_err(|e| format!("{e:?}"))?;
        Ok(Self { symbolic, values })
    }

    /// `rhs ← A⁻¹ rhs`.
    pub(crate) fn solve_in_place(&self, rhs: MatMut<'_, f64>) {
        let factor = LltRef::new(&self.symbolic, &self.values);
        let mut groups = Vec::new();
        let mut rest = rhs;
        while rest.ncols() > COLUMNS_PER_TASK {
            let (head, tail) = rest.split_at_col_mut(COLUMNS_PER_TASK);
            groups.push(head);
            rest = tail;
        }
        groups.push(rest);
        groups.into_par_iter().for_each(|group| {
            let mut scratch =
                MemBuffer::new(factor.solve_in_place_scratch::<f64>(group.ncols(), Par::Seq));
            factor.solve_in_place_with_conj(Conj::No, group, Par::Seq, MemStack::new(&mut scratch));
        });
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
}
