//! Dense products of a tall matrix, split by fixed blocks of rows over the threads, each block
//! sequential: the re-orthogonalisation and Ritz-vector products of the eigen-solver. faer's
//! parallel kernels synchronise many times per product, which on a small machine whose cores
//! are shared cost more than they gained (docs/geometry.md). Fixed blocks, and partial sums
//! added in block order, keep every result independent of the thread count.

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatMut, MatRef, Par};
use rayon::prelude::*;

/// Rows per task: enough work to hide the scheduling, small enough to balance two threads.
const ROWS_PER_TASK: usize = 2048;

/// `W ← W − Q (Qᵀ W)`, returning `Qᵀ W` (one classical Gram-Schmidt pass of the columns of `w`
/// against the orthonormal columns of `q`).
pub(crate) fn subtract_projection(q: MatRef<'_, f64>, w: MatMut<'_, f64>) -> Mat<f64> {
    let coefficients = transpose_product(q, w.as_ref());
    for_row_blocks(w, |start, mut rows| {
        let q = q.subrows(start, rows.nrows());
        matmul(rows.as_mut(), Accum::Add, q, &coefficients, -1.0, Par::Seq);
    });
    coefficients
}

/// `Aᵀ B`: one partial product per block of rows, summed in block order.
pub(crate) fn transpose_product(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let partial: Vec<Mat<f64>> = (0..a.nrows().div_ceil(ROWS_PER_TASK))
        .into_par_iter()
        .map(|block| {
            let (start, len) = row_block(a.nrows(), block);
            // As (Bᵀ A)ᵀ: the narrow B is the packed operand and the wide A streams through
            // (about 10% faster for the Lanczos basis against a block, docs/geometry.md).
            let mut c = Mat::zeros(b.ncols(), a.ncols());
            matmul(
                c.as_mut(),
                Accum::Replace,
                b.subrows(start, len).transpose(),
                a.subrows(start, len),
                1.0,
                Par::Seq,
            );
            c
        })
        .collect();
    let mut sum = Mat::zeros(a.ncols(), b.ncols());
    for c in &partial {
        sum += c.transpose();
    }
    sum
}

/// `A B`.
pub(crate) fn product(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let mut out = Mat::zeros(a.nrows(), b.ncols());
    for_row_blocks(out.as_mut(), |start, mut rows| {
        let a = a.subrows(start, rows.nrows());
        matmul(rows.as_mut(), Accum::Replace, a, b, 1.0, Par::Seq);
    });
    out
}

/// `(start, length)` of row block `block` of `rows` rows.
fn row_block(rows: usize, block: usize) -> (usize, usize) {
    let start = block * ROWS_PER_TASK;
    (start, ROWS_PER_TASK.min(rows - start))
}

/// Calls `f(start, rows)` on every block of rows of `m`, in parallel.
fn for_row_blocks(m: MatMut<'_, f64>, f: impl Fn(usize, MatMut<'_, f64>) + Sync) {
    let mut blocks = Vec::new();
    let mut rest = m;
    let mut start = 0;
    while rest.nrows() > ROWS_PER_TASK {
        let (head, tail) = rest.split_at_row_mut(ROWS_PER_TASK);
        blocks.push((start, head));
        start += ROWS_PER_TASK;
        rest = tail;
    }
    blocks.push((start, rest));
    blocks
        .into_par_iter()
        .for_each(|(start, rows)| f(start, rows));
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pseudo_random(rows: usize, cols: usize, seed: u64) -> Mat<f64> {
        Mat::from_fn(rows, cols, |i, j| {
            let x = (i as u64 * 7919 + j as u64 * 104_729 + seed).wrapping_mul(2_654_435_761);
            (x % 1000) as f64 / 500.0 - 1.0
        })
    }

    #[test]
    fn products_equal_the_plain_ones_across_block_edges() {
        for rows in [1, ROWS_PER_TASK, ROWS_PER_TASK + 3, 3 * ROWS_PER_TASK - 1] {
            let q = pseudo_random(rows, 5, 1);
            let w = pseudo_random(rows, 3, 2);
            let mut projected = w.clone();
            let c = subtract_projection(q.as_ref(), projected.as_mut());
            let expected_c = q.transpose() * &w;
            let expected_w = &w - &q * &expected_c;
            assert!((&c - &expected_c).norm_max() < 1e-9 * rows as f64);
            assert!((&projected - &expected_w).norm_max() < 1e-9 * rows as f64);
            let b = pseudo_random(5, 4, 3);
            assert!((product(q.as_ref(), b.as_ref()) - &q * &b).norm_max() < 1e-12);
            let gram = transpose_product(q.as_ref(), w.as_ref());
            assert!((&gram - q.transpose() * &w).norm_max() < 1e-9 * rows as f64);
        }
    }
}
