//! The first `k` eigenpairs of the cotangent Laplacian, `L x = λ M x` with the lumped mass
//! matrix `M` — the spectral basis of the Laplacian error LE (thesis eq. 6.16: MSE over the
//! first 150 eigenvectors) and of spectral mesh processing in general (Lévy, "Laplace-Beltrami
//! eigenfunctions", SMI 2006; Vallet and Lévy, "Spectral geometry processing with manifold
//! harmonics", Eurographics 2008).
//!
//! # Method
//! With `M` diagonal the problem is the symmetric `A y = λ y`, `A = M^{-1/2} L M^{-1/2}`,
//! `x = M^{-1/2} y`. Shift-invert around `σ` turns the eigenvalues nearest `σ` into the
//! largest `|μ|`, `μ = 1/(λ − σ)`, of `M^{1/2} (L − σM)^{-1} M^{1/2}`; block Lanczos with full
//! re-orthogonalisation (block classical Gram-Schmidt, a second pass only for a block that
//! lost most of its norm; each new block orthonormalised by Cholesky QR twice) builds a
//! Krylov basis, one sparse factorisation of `L − σM` (faer, AMD fill-reducing ordering)
//! serves every solve, and a dense symmetric eigen-solve of the small projected matrix gives
//! Ritz pairs; the basis is extended until every wanted Ritz residual is below `1e-6 |μ|`.
//!
//! The shift is *inside* the spectrum, at 0.45 of Weyl's estimate `4πk/A` of `λ_k`: the
//! wanted eigenvalues then lie on both sides of it, the slowest to converge is about twice as
//! far (relatively) from the first unwanted one as with a shift at zero, and the basis needs
//! about a third fewer vectors (481 instead of 697-721 for 150 pairs of a 45k-vertex mesh;
//! docs/geometry.md). `L − σM` is then indefinite: it is factorised as `L D Lᵀ` without
//! pivoting (a pivot below `1e-10` of the largest rejects it), and the pairs are accepted only
//! if they hold every eigenvalue below `σ` — Sylvester's law of inertia counts them as the
//! negative pivots of `D`. When the estimate is too high (borders, thin parts make the
//! spectrum denser) or anything fails, the shift just below zero, where `L − σM` is positive
//! definite (`L Lᵀ`) and the nearest are the smallest, runs instead.
//!
//! Last, one step of block inverse iteration with the same factor and a Rayleigh-Ritz
//! projection with `A` itself: Krylov vectors collect high-frequency rounding that the
//! shift-inverted operator hides and `A` amplifies (sliver triangles, masses down to 1e-11);
//! one more solve damps it by `|λ − σ| / |λ_high − σ|`. It brings the worst residual
//! `‖Lx − λMx‖ / ‖Mx‖` of 150 pairs of a real scan from 2.4e-4 λ_max (the earlier solver,
//! converged to 1e-9) to 2.2e-7 λ_max, and the eigenvalues agree with the unrefined ones and
//! scipy's to 2e-11 or better. Memory is `#V × O(k)`, never `#V²`. The dense products run on fixed
//! blocks of rows and the solves on fixed groups of columns, in parallel, each sequential inside
//! (`row_chunked_products`, `sparse_cholesky`): faer's finer-grained parallel kernels made the
//! solver 2-3× slower than one thread on a 2-core machine (docs/geometry.md), and fixed blocks
//! keep the result independent of the thread count.
//!
//! The null vector `M^{1/2}·1` (λ = 0) is known and locked at the start of the basis: below
//! zero the iteration then sees `μ` from `1/λ₁` down, instead of from `1/|σ| ≈ 1e8/λ-scale`, a
//! range that would amplify rounding along the null vector every step (and made a single
//! Gram-Schmidt pass diverge on a 4.5k-vertex mesh before the null vector was locked).
//!
//! Each connected component is solved on its own (its eigenpairs are those of the whole
//! operator, and a zero eigenvalue per component would otherwise defeat single-vector
//! Krylov methods); the `k` smallest over all components are kept. Components of at most
//! 600 vertices use a dense eigen-solve, and so do components of at most 3 000 whose Lanczos
//! basis reached its cap unconverged with both shifts (a 1 029-vertex QEM output of a
//! synthetic creature with 150 pairs wanted stalled at 852 vectors with the shift below zero
//! and a tolerance of 1e-9; the interior shift converges there).
//!
//! # Conventions
//! - `values` ascending (`≥ 0` up to rounding; one zero per component); `vectors` `#V×k`
//!   M-orthonormal, `Xᵀ M X = I`, column `i` for `values[i]`.
//! - Sign: the entry of largest magnitude of each vector is positive (the first such entry on
//!   ties), so the result is reproducible and comparable across meshes.
//! - Vertices with zero mass (unreferenced, or only in degenerate faces) are not part of the
//!   surface: their rows are zero.

use faer::sparse::{SparseColMat, Triplet};
use faer::{Mat, MatRef, Side};
use petgraph::unionfind::UnionFind;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rayon::prelude::*;

use crate::TriMesh;
use crate::cotangent_laplacian::cotangent_laplacian;
use crate::error::{Error, Result};
use crate::mass_matrix::lumped_mass_matrix;
use crate::row_chunked_products::{product, subtract_projection, transpose_product};
use crate::sparse_cholesky::SparseCholesky;

/// The first `k` generalised eigenpairs of the cotangent Laplacian.
#[derive(Debug, Clone)]
pub struct LaplacianEigenpairs {
    /// Eigenvalues `λ_0 ≤ … ≤ λ_{k−1}`.
    pub values: Vec<f64>,
    /// Eigenvectors, `#V×k`, M-orthonormal, column `i` for `values[i]`.
    pub vectors: Mat<f64>,
}

/// Components up to this size are solved densely.
const DENSE_LIMIT: usize = 600;
/// Components up to this size are solved densely when block Lanczos does not converge.
const DENSE_FALLBACK_LIMIT: usize = 3000;
/// Relative Ritz residual accepted for convergence.
const TOLERANCE: f64 = 1e-6;
/// The interior shift as a fraction of Weyl's estimate of the largest wanted eigenvalue.
const INTERIOR_SHIFT: f64 = 0.45;
/// Largest Lanczos block.
const MAX_BLOCK: usize = 24;
/// A Gram-Schmidt pass is repeated when a column keeps less than this fraction of its norm:
/// one pass leaves an orthogonality error of about ε divided by that fraction (every step on
/// the 41k-vertex bumpy sphere keeps ≥ 0.33, so it takes one pass each).
const REORTHOGONALIZE_BELOW: f64 = 0.1;

/// The `k` smallest eigenpairs of `L x = λ M x` (cotangent `L`, lumped `M`) of `mesh`; see the
/// module documentation. Fails on a mesh without faces of positive area, on `k = 0`, on `k`
/// larger than the number of surface vertices, or if the solver does not converge.
///
/// ```
/// use meshgnn_geometry::{icosphere, laplacian_eigenvectors};
/// let pairs = laplacian_eigenvectors(&icosphere(3), 4)?;
/// assert!(pairs.values[0].abs() < 1e-8);
/// // The l = 1 spherical harmonics: λ ≈ l(l + 1) = 2, three times.
/// assert!(pairs.values[1..].iter().all(|&l| (l - 2.0).abs() < 0.02));
/// assert_eq!(pairs.vectors.shape(), (642, 4));
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn laplacian_eigenvectors(mesh: &TriMesh, k: usize) -> Result<LaplacianEigenpairs> {
    if k == 0 {
        return Err(Error::InvalidParameter {
            name: "k",
            message: "ask for at least one eigenpair".into(),
        });
    }
    let mass = lumped_mass_matrix(mesh);
    let active = mass.iter().filter(|&&m| m > 0.0).count();
    if active == 0 {
        return Err(Error::Empty {
            what: "mesh surface (no face of positive area)",
        });
    }
    if k > active {
        return Err(Error::InvalidParameter {
            name: "k",
            message: format!("asked for {k} eigenpairs of a surface with {active} vertices"),
        });
    }

    let laplacian = cotangent_laplacian(mesh)?;
    let components = surface_components(&laplacian, &mass);
    // (λ, component, local index) of every candidate, and the local eigenvectors.
    let mut candidates: Vec<(f64, usize, usize)> = Vec::new();
    let mut solutions: Vec<(Vec<f64>, Mat<f64>)> = Vec::with_capacity(components.len());
    for (c, vertices) in components.iter().enumerate() {
        let want = k.min(vertices.len());
        let (values, vectors) = component_eigenpairs(&laplacian, &mass, vertices, want)?;
        candidates.extend(values.iter().enumerate().map(|(i, &l)| (l, c, i)));
        solutions.push((values, vectors));
    }
    candidates.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    candidates.truncate(k);
    let mut vectors = Mat::<f64>::zeros(mesh.vertex_count(), k);
    let mut values = Vec::with_capacity(k);
    // x = M^{-1/2} y.
    let inverse_sqrt_mass: Vec<f64> = mass.iter().map(|m| 1.0 / m.sqrt()).collect();
    for (column, &(value, c, i)) in candidates.iter().enumerate() {
        values.push(value);
        let local = solutions[c].1.col(i);
        let mut out = vectors.col_mut(column);
        for (row, &v) in components[c].iter().enumerate() {
            out[v] = local[row] * inverse_sqrt_mass[v];
        }
        // Sign convention: largest-magnitude entry positive.
        let mut best = (0usize, 0.0f64);
        for row in 0..out.nrows() {
            if out[row].abs() > best.1.abs() {
                best = (row, out[row]);
            }
        }
        if best.1 < 0.0 {
            for row in 0..out.nrows() {
                out[row] = -out[row];
            }
        }
    }
    Ok(LaplacianEigenpairs { values, vectors })
}

/// Vertices with positive mass grouped by the connectivity of `laplacian`'s stored entries,
/// each group ascending, groups ordered by their smallest vertex.
fn surface_components(laplacian: &SparseColMat<usize, f64>, mass: &[f64]) -> Vec<Vec<usize>> {
    let n = mass.len();
    let mut sets = UnionFind::<usize>::new(n);
    let symbolic = laplacian.symbolic();
    for col in 0..n {
        for &row in symbolic.row_idx_of_col_raw(col) {
            sets.union(row, col);
        }
    }
    let roots = sets.into_labeling();
    let mut index_of_root = vec![usize::MAX; n];
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for v in (0..n).filter(|&v| mass[v] > 0.0) {
        let root = roots[v];
        if index_of_root[root] == usize::MAX {
            index_of_root[root] = groups.len();
            groups.push(Vec::new());
        }
        groups[index_of_root[root]].push(v);
    }
    groups
}

/// The `want` smallest eigenpairs `(λ ascending, y: n×want orthonormal)` of
/// `M^{-1/2} L M^{-1/2}` restricted to `vertices`.
fn component_eigenpairs(
    laplacian: &SparseColMat<usize, f64>,
    mass: &[f64],
    vertices: &[usize],
    want: usize,
) -> Result<(Vec<f64>, Mat<f64>)> {
    let n = vertices.len();
    let mut local = vec![usize::MAX; mass.len()];
    for (i, &v) in vertices.iter().enumerate() {
        local[v] = i;
    }
    let sqrt_mass: Vec<f64> = vertices.iter().map(|&v| mass[v].sqrt()).collect();
    // The component's block of L, in local indices: (row, col, value).
    let mut entries = Vec::new();
    for (j, &v) in vertices.iter().enumerate() {
        let rows = laplacian.symbolic().row_idx_of_col_raw(v);
        let vals = laplacian.val_of_col(v);
        for (&row, &value) in rows.iter().zip(vals) {
            if let Some(&i) = local.get(row).filter(|&&i| i != usize::MAX) {
                entries.push(Triplet::new(i, j, value));
            }
        }
    }
    if n <= DENSE_LIMIT {
        return dense_eigenpairs(&entries, &sqrt_mass, want);
    }
    let null = null_vector(&sqrt_mass);
    if want == 1 {
        return Ok((vec![0.0], null.as_mat().to_owned()));
    }
    // A shift just below zero, relative to the typical eigenvalue scale mean(L_ii / M_ii):
    // `L − σM` is positive definite.
    let scale = entries
        .iter()
        .filter(|t| t.row == t.col)
        .map(|t| t.val / (sqrt_mass[t.row] * sqrt_mass[t.row]))
        .sum::<f64>()
        / n as f64;
    let below_zero = -1e-8 * scale.max(f64::MIN_POSITIVE);
    // Weyl's law for a closed surface of area A, N(λ) ≈ A λ / 4π, estimates λ_want; shifting
    // to a fraction of it puts the wanted λ on both sides of the shift. A component whose
    // spectrum is denser (borders, thin parts) can put the shift too high: the inertia check
    // rejects the result, and the shift below zero is always valid.
    let area: f64 = sqrt_mass.iter().map(|m| m * m).sum();
    let weyl = 4.0 * std::f64::consts::PI * want as f64 / area;
    let shift = INTERIOR_SHIFT * weyl;
    let interior = shifted_factor(&entries, &sqrt_mass, shift).and_then(|factor| {
        shift_invert_subspace(&factor, &sqrt_mass, &null, want, shift).map(|y| (factor, y))
    });
    let (factor, subspace) = match interior {
        Ok(found) => found,
        Err(_) => {
            let definite = shifted_factor(&entries, &sqrt_mass, below_zero)?;
            match shift_invert_subspace(&definite, &sqrt_mass, &null, want, below_zero) {
                Ok(y) => (definite, y),
                Err(_) if n <= DENSE_FALLBACK_LIMIT => {
                    return dense_eigenpairs(&entries, &sqrt_mass, want);
                }
                Err(e) => return Err(e),
            }
        }
    };
    refined_pairs(&entries, &sqrt_mass, &factor, &null, subspace)
}

/// The component's null vector `M^{1/2}·1`, normalised (`L·1 = 0`).
fn null_vector(sqrt_mass: &[f64]) -> faer::Col<f64> {
    let norm = sqrt_mass.iter().map(|m| m * m).sum::<f64>().sqrt();
    faer::Col::<f64>::from_fn(sqrt_mass.len(), |i| sqrt_mass[i] / norm)
}

/// The factor of `L − σM` (local `entries` of `L`, `sqrt_mass` = `M^{1/2}`): `L Lᵀ` below
/// zero, `L D Lᵀ` inside the spectrum.
fn shifted_factor(
    entries: &[Triplet<usize, usize, f64>],
    sqrt_mass: &[f64],
    sigma: f64,
) -> Result<SparseCholesky> {
    let n = sqrt_mass.len();
    let failure = |message: String| Error::Solver {
        solver: "laplacian eigenvectors",
        message,
    };
    let shifted: Vec<Triplet<usize, usize, f64>> = entries
        .iter()
        .map(|t| {
            let diagonal = if t.row == t.col {
                -sigma * sqrt_mass[t.row] * sqrt_mass[t.row]
            } else {
                0.0
            };
            Triplet::new(t.row, t.col, t.val + diagonal)
        })
        .collect();
    let matrix = SparseColMat::try_new_from_triplets(n, n, &shifted)
        .map_err(|e| failure(format!("assembling L - σM: {e:?}")))?;
    if sigma < 0.0 {
        SparseCholesky::new(matrix.as_ref())
    } else {
        SparseCholesky::new_indefinite(matrix.as_ref())
    }
    .map_err(|e| failure(format!("factorising L - σM (σ = {sigma:e}): {e}")))
}

/// An orthonormal basis `n×want` (the null vector first) of the `want` eigenvectors of
/// `M^{-1/2} L M^{-1/2}` nearest `sigma`, by shift-invert block Lanczos with `factor` of
/// `L − σM`. Inside the spectrum they are the smallest `want` only if they hold every
/// eigenvalue below the shift, counted by Sylvester's law of inertia (the negative pivots).
fn shift_invert_subspace(
    factor: &SparseCholesky,
    sqrt_mass: &[f64],
    null: &faer::Col<f64>,
    want: usize,
    sigma: f64,
) -> Result<Mat<f64>> {
    // op(Y) = M^{1/2} (L − σM)^{-1} M^{1/2} Y, in place.
    let op = |mut y: Mat<f64>| -> Mat<f64> {
        scale_rows(&mut y, sqrt_mass);
        factor.solve_in_place(y.as_mut());
        scale_rows(&mut y, sqrt_mass);
        y
    };
    // The null vector y₀ is known: lock it instead of letting Lanczos find it. Below zero the
    // shift would otherwise make it dominate the operator (1/|σ| ≈ 1e8 against 1/λ₁), and
    // rounding along it would be amplified that much every step.
    let (mu, vectors) = block_lanczos(sqrt_mass.len(), want - 1, null.as_ref(), op)?;
    if let Some(negative) = factor.negative_eigenvalues() {
        // λ₀ = 0 < σ is among the negative eigenvalues of L − σM.
        let below = 1 + mu.iter().filter(|&&m| m < 0.0).count();
        if below != negative {
            return Err(Error::Solver {
                solver: "laplacian eigenvectors",
                message: format!(
                    "the shift σ = {sigma:e} has {negative} eigenvalues below it, the pairs \
                     found {below}"
                ),
            });
        }
    }
    Ok(vectors)
}

/// The eigenpairs `(λ ascending, y)` of `M^{-1/2} L M^{-1/2}` from a converged subspace `y`
/// (null vector first): one step of block inverse iteration with the `factor` the subspace
/// came from, which damps the high-frequency rounding that Krylov vectors collect on a mesh
/// whose `M^{-1/2} L M^{-1/2}` has a large norm, then Rayleigh-Ritz with `L` itself.
fn refined_pairs(
    entries: &[Triplet<usize, usize, f64>],
    sqrt_mass: &[f64],
    factor: &SparseCholesky,
    null: &faer::Col<f64>,
    subspace: Mat<f64>,
) -> Result<(Vec<f64>, Mat<f64>)> {
    let n = sqrt_mass.len();
    let width = subspace.ncols() - 1;
    let mut z = subspace.subcols(1, width).to_owned();
    drop(subspace);
    scale_rows(&mut z, sqrt_mass);
    factor.solve_in_place(z.as_mut());
    scale_rows(&mut z, sqrt_mass);
    for _ in 0..2 {
        subtract_projection(null.as_mat(), z.as_mut());
    }
    for j in 0..z.ncols() {
        let norm = z.col(j).squared_norm_l2().sqrt();
        let mut col = z.col_mut(j);
        for i in 0..n {
            col[i] /= norm;
        }
    }
    let az = scaled_laplacian_product(entries, sqrt_mass, &z);
    // Rayleigh-Ritz on the span of Z: H u = λ G u with G = ZᵀZ (near the identity: the
    // columns are unit and nearly orthogonal), as G = L Lᵀ, L⁻¹ H L⁻ᵀ.
    let gram = symmetrized(transpose_product(z.as_ref(), z.as_ref()).as_ref());
    let h = symmetrized(transpose_product(z.as_ref(), az.as_ref()).as_ref());
    drop(az);
    let failure = |message: String| Error::Solver {
        solver: "laplacian eigenvectors",
        message,
    };
    let lower = gram
        .llt(Side::Lower)
        .map_err(|e| failure(format!("refined basis is not independent: {e:?}")))?
        .L()
        .to_owned();
    let mut inverse = Mat::<f64>::zeros(width, width);
    faer::linalg::triangular_inverse::invert_lower_triangular(
        inverse.as_mut(),
        lower.as_ref(),
        faer::Par::Seq,
    );
    let reduced = symmetrized((&inverse * &h * inverse.transpose()).as_ref());
    let eigen = reduced
        .self_adjoint_eigen(Side::Lower)
        .map_err(|e| failure(format!("Rayleigh-Ritz eigen-solve did not converge: {e:?}")))?;
    let coefficients = inverse.transpose() * eigen.U();
    let mut vectors = Mat::<f64>::zeros(n, width + 1);
    vectors.col_mut(0).copy_from(null);
    vectors
        .subcols_mut(1, width)
        .copy_from(product(z.as_ref(), coefficients.as_ref()));
    let values = std::iter::once(0.0)
        .chain((0..width).map(|i| eigen.S()[i]))
        .collect();
    Ok((values, vectors))
}

/// `M^{-1/2} L M^{-1/2} Z` from the local `entries` of `L` (listed column by column; `L` is
/// symmetric, so column `j`'s entries are row `j`'s), in fixed groups of columns over the
/// threads (each output column is computed alone: the result does not depend on them).
fn scaled_laplacian_product(
    entries: &[Triplet<usize, usize, f64>],
    sqrt_mass: &[f64],
    z: &Mat<f64>,
) -> Mat<f64> {
    const GROUP: usize = 8;
    let n = sqrt_mass.len();
    let mut column_start = vec![0usize; n + 1];
    for t in entries {
        column_start[t.col + 1] += 1;
    }
    for j in 0..n {
        column_start[j + 1] += column_start[j];
    }
    let inverse_sqrt: Vec<f64> = sqrt_mass.iter().map(|m| 1.0 / m).collect();
    let mut out = Mat::<f64>::zeros(n, z.ncols());
    let mut groups = Vec::new();
    let mut rest = out.as_mut();
    let mut first = 0;
    while rest.ncols() > 0 {
        let width = rest.ncols().min(GROUP);
        let (head, tail) = rest.split_at_col_mut(width);
        groups.push((first, head));
        first += width;
        rest = tail;
    }
    let buffers = || (vec![[0.0f64; GROUP]; n], vec![[0.0f64; GROUP]; n]);
    groups
        .into_par_iter()
        .for_each_init(buffers, |(scaled, sums), (first, mut group)| {
            let width = group.ncols();
            // The group's rows of M^{-1/2} Z side by side: one entry of L reads one short run.
            for c in 0..width {
                let x = z.col(first + c);
                for (i, row) in scaled.iter_mut().enumerate() {
                    row[c] = x[i] * inverse_sqrt[i];
                }
            }
            for (j, sum) in sums.iter_mut().enumerate() {
                *sum = [0.0; GROUP];
                for t in &entries[column_start[j]..column_start[j + 1]] {
                    let row = &scaled[t.row];
                    for c in 0..GROUP {
                        sum[c] += t.val * row[c];
                    }
                }
            }
            for c in 0..width {
                let mut col = group.as_mut().col_mut(c);
                for (j, sum) in sums.iter().enumerate() {
                    col[j] = sum[c] * inverse_sqrt[j];
                }
            }
        });
    out
}

/// Multiplies row `i` of `y` by `factors[i]`.
fn scale_rows(y: &mut Mat<f64>, factors: &[f64]) {
    for j in 0..y.ncols() {
        let mut col = y.col_mut(j);
        for (i, &f) in factors.iter().enumerate() {
            col[i] *= f;
        }
    }
}

/// Dense solve of `M^{-1/2} L M^{-1/2}` for a small component.
fn dense_eigenpairs(
    entries: &[Triplet<usize, usize, f64>],
    sqrt_mass: &[f64],
    want: usize,
) -> Result<(Vec<f64>, Mat<f64>)> {
    let n = sqrt_mass.len();
    let mut a = Mat::<f64>::zeros(n, n);
    for t in entries {
        a[(t.row, t.col)] += t.val / (sqrt_mass[t.row] * sqrt_mass[t.col]);
    }
    let eigen = a
        .self_adjoint_eigen(Side::Lower)
        .map_err(|e| Error::Solver {
            solver: "laplacian eigenvectors",
            message: format!("dense eigen-solve did not converge: {e:?}"),
        })?;
    let values = (0..want).map(|i| eigen.S()[i]).collect();
    let vectors = eigen.U().subcols(0, want).to_owned();
    Ok((values, vectors))
}

/// The `want` eigenpairs of largest magnitude `(μ by decreasing |μ|, vectors)` of the
/// symmetric operator `op` restricted to the complement of its unit eigenvector `locked`, by
/// block Lanczos with full re-orthogonalisation; `vectors` is `n×(want + 1)`, `locked` first.
fn block_lanczos(
    n: usize,
    want: usize,
    locked: faer::ColRef<'_, f64>,
    op: impl Fn(Mat<f64>) -> Mat<f64>,
) -> Result<(Vec<f64>, Mat<f64>)> {
    let block = want.clamp(1, MAX_BLOCK);
    let capacity = n.min(4 * want + 8 * block + 64);
    // Grown block by block: only the columns used are ever touched.
    let mut basis = Mat::<f64>::with_capacity(n, capacity);
    basis.resize_with(n, 1, |_, _| 0.0);
    let mut projected = Mat::<f64>::zeros(capacity, capacity);
    let mut rng = StdRng::seed_from_u64(0x5eed_1a9c);
    let mut next = Mat::<f64>::from_fn(n, block, |_, _| rng.random_range(-1.0..1.0));
    // Column 0 holds `locked`; `op` is never applied to it, so its row and column of the
    // projected matrix stay zero and its Ritz value 0 is never among the wanted.
    basis.col_mut(0).copy_from(locked);
    for _ in 0..2 {
        let c = locked.transpose() * &next;
        next -= locked.as_mat() * c.as_mat();
    }
    let (v0, _) = orthonormalize(&mut next, basis.subcols(0, 1), n - 1, &mut rng);
    append_columns(&mut basis, &v0);
    let mut size = 1 + v0.ncols();
    let mut current = (1, v0.ncols());
    // Ritz checks cost O(size³): start once the basis can hold the wanted pairs plus a block;
    // then, as the worst residual falls geometrically with the basis size, where the last two
    // checks extrapolate it to reach the tolerance — at least a block and at most
    // max(block, size/8) further.
    let mut next_check = want + block;
    let mut last_check: Option<(usize, f64)> = None;
    loop {
        let (start, width) = current;

        let mut w = op(basis.subcols(start, width).to_owned());
        // Block classical Gram-Schmidt against the whole basis, repeated when a column lost
        // more than `1 − REORTHOGONALIZE_BELOW` of its norm (the DGKS test).
        let q = basis.subcols(0, size);
        let mut coefficients = Mat::<f64>::zeros(size, width);
        let before = column_norms(&w);
        for pass in 0..2 {
            coefficients += subtract_projection(q, w.as_mut());
            let after = column_norms(&w);
            let kept = before
                .iter()
                .zip(&after)
                .all(|(b, a)| *a >= REORTHOGONALIZE_BELOW * b);
            if pass == 0 && kept {
                break;
            }
        }
        // Row 0 (along `locked`) is rounding only: the deflated operator has none.
        coefficients.row_mut(0).fill(0.0);
        projected
            .submatrix_mut(0, start, size, width)
            .copy_from(&coefficients);
        // The new block V and R with W = V R (exactly representable once the space is full).
        let (fresh, r) = orthonormalize(&mut w, q, n - size, &mut rng);
        if size >= next_check || fresh.ncols() == 0 || size + fresh.ncols() > capacity {
            let h = symmetrized(projected.submatrix(0, 0, size, size));
            let eigen = h
                .self_adjoint_eigen(Side::Lower)
                .map_err(|e| Error::Solver {
                    solver: "laplacian eigenvectors",
                    message: format!("projected eigen-solve did not converge: {e:?}"),
                })?;
            let s = eigen.U();
            // Ritz pairs by decreasing |θ|; the residual of pair i is |R s_i(last block)|.
            let mut order: Vec<usize> = (0..size).collect();
            order.sort_by(|&a, &b| {
                let (ta, tb) = (eigen.S()[a].abs(), eigen.S()[b].abs());
                tb.total_cmp(&ta).then(b.cmp(&a))
            });
            let theta: Vec<f64> = order.iter().map(|&i| eigen.S()[i]).collect();
            let worst = (0..want)
                .map(|i| {
                    let tail = s.col(order[i]).subrows(start, width);
                    (&r * tail).norm_l2() / theta[i].abs()
                })
                .fold(0.0f64, f64::max);
            let converged = worst <= TOLERANCE;
            next_check = size + next_check_distance(last_check, (size, worst), block);
            last_check = Some((size, worst));
            if converged || fresh.ncols() == 0 {
                // Column 0 of the result is `locked` itself: e₀ in the basis' coordinates.
                let mut selected = Mat::<f64>::zeros(size, want + 1);
                selected[(0, 0)] = 1.0;
                for (i, &pair) in order[..want].iter().enumerate() {
                    selected.col_mut(i + 1).copy_from(s.col(pair));
                }
                let vectors = product(basis.subcols(0, size), selected.as_ref());
                return Ok((theta[..want].to_vec(), vectors));
            }
            if size + fresh.ncols() > capacity {
                return Err(Error::Solver {
                    solver: "laplacian eigenvectors",
                    message: format!(
                        "block Lanczos did not converge within a basis of {capacity} vectors"
                    ),
                });
            }
        }
        projected
            .submatrix_mut(size, start, r.nrows(), width)
            .copy_from(&r);
        append_columns(&mut basis, &fresh);
        current = (size, fresh.ncols());
        size += fresh.ncols();
    }
}

/// How many vectors the basis should grow before the next Ritz check, given the last two
/// checks `(basis size, worst relative residual)`: where the log-linear extrapolation reaches
/// `TOLERANCE`, clamped to `[block, max(block, size/8)]` (the upper end alone when the
/// residual did not fall).
fn next_check_distance(
    previous: Option<(usize, f64)>,
    (size, worst): (usize, f64),
    block: usize,
) -> usize {
    let longest = block.max(size / 8);
    let Some((before, earlier)) = previous.filter(|&(_, earlier)| earlier > worst) else {
        return longest;
    };
    let decades_per_vector = (earlier / worst).log10() / (size - before) as f64;
    let needed = (worst / TOLERANCE).log10().max(0.0) / decades_per_vector;
    (needed.ceil() as usize).clamp(block, longest)
}

/// Appends the columns of `new` to `basis` (within its reserved capacity).
fn append_columns(basis: &mut Mat<f64>, new: &Mat<f64>) {
    let old = basis.ncols();
    basis.resize_with(basis.nrows(), old + new.ncols(), |i, j| new[(i, j - old)]);
}

/// The Euclidean norm of every column of `w`, unscaled (the columns hold values of order
/// `|μ|`, far from overflow; faer's overflow-safe `norm_l2` took as long as the
/// re-orthogonalisation products, docs/geometry.md).
fn column_norms(w: &Mat<f64>) -> Vec<f64> {
    (0..w.ncols())
        .map(|j| w.col(j).squared_norm_l2().sqrt())
        .collect()
}

/// `(H + Hᵀ) / 2`.
fn symmetrized(h: MatRef<'_, f64>) -> Mat<f64> {
    Mat::from_fn(h.nrows(), h.ncols(), |i, j| 0.5 * (h[(i, j)] + h[(j, i)]))
}

/// Orthonormalises the columns of `w` (already orthogonal to `q`), keeping `room` columns:
/// returns `(V, R)` with `W ≈ V R` for the kept part. Cholesky QR twice when `W` is well
/// conditioned (BLAS-3, split by rows over the threads); otherwise modified Gram-Schmidt
/// twice, where a column that is numerically dependent is replaced by a random vector
/// orthogonal to everything (its row of `R` is zero), so the block keeps its width through
/// invariant subspaces.
fn orthonormalize(
    w: &mut Mat<f64>,
    q: MatRef<'_, f64>,
    room: usize,
    rng: &mut StdRng,
) -> (Mat<f64>, Mat<f64>) {
    let kept = room.min(w.ncols()).min(w.nrows().saturating_sub(q.ncols()));
    if kept == w.ncols()
        && let Some(qr) = cholesky_qr(w)
    {
        return qr;
    }
    gram_schmidt(w, q, kept, rng)
}

/// CholQR2 (Fukaya et al., 2014): `R₁ᵀR₁ = WᵀW`, `V₁ = W R₁⁻¹`, the same again on `V₁`, and
/// `R = R₂ R₁`; orthogonal to rounding while `cond(W)` stays well below `ε^{-1/2} ≈ 10⁸`. The
/// second pass runs only when `V₁` is not orthonormal to 1e-12 (the Gram matrix that checks
/// it is the one the second pass needs): a Lanczos block fresh from re-orthogonalisation is
/// well conditioned, and one pass leaves it orthonormal to about 1e-15 (every block of a
/// 45k-vertex scan but the random first one). `None` when `W` may not be (a Cholesky fails, a
/// diagonal of `R₁` or `R₂` is below 1e-5 of the largest, or `V` is not orthonormal to 1e-12
/// after the second pass).
fn cholesky_qr(w: &Mat<f64>) -> Option<(Mat<f64>, Mat<f64>)> {
    let width = w.ncols();
    let mut v = w.clone();
    let mut r = Mat::<f64>::identity(width, width);
    let mut gram = transpose_product(v.as_ref(), v.as_ref());
    for _ in 0..2 {
        let factor = gram.llt(Side::Lower).ok()?;
        let upper = factor.L().transpose().to_owned();
        let diagonal = (0..width).map(|i| upper[(i, i)]);
        let (low, high) = diagonal.fold((f64::INFINITY, 0.0f64), |(lo, hi), d| {
            (lo.min(d), hi.max(d))
        });
        if low.is_nan() || low <= 1e-5 * high {
            return None;
        }
        let mut inverse = Mat::<f64>::zeros(width, width);
        faer::linalg::triangular_inverse::invert_upper_triangular(
            inverse.as_mut(),
            upper.as_ref(),
            faer::Par::Seq,
        );
        v = product(v.as_ref(), inverse.as_ref());
        r = &upper * &r;
        gram = transpose_product(v.as_ref(), v.as_ref());
        let error = (&gram - Mat::<f64>::identity(width, width)).norm_max();
        if error <= 1e-12 {
            return Some((v, r));
        }
    }
    None
}

/// Modified Gram-Schmidt, twice, keeping `kept` columns; see [`orthonormalize`].
fn gram_schmidt(
    w: &mut Mat<f64>,
    q: MatRef<'_, f64>,
    kept: usize,
    rng: &mut StdRng,
) -> (Mat<f64>, Mat<f64>) {
    let n = w.nrows();
    let width = w.ncols();
    let mut v = Mat::<f64>::zeros(n, kept);
    let mut r = Mat::<f64>::zeros(kept, width);
    let mut filled = 0usize;
    for j in 0..width {
        let original = w.col(j).norm_l2();
        let mut col = w.col(j).to_owned();
        for _ in 0..2 {
            for i in 0..filled {
                let c = v.col(i).transpose() * &col;
                col -= c * v.col(i);
                r[(i, j)] += c;
            }
        }
        let norm = col.norm_l2();
        if filled < kept {
            if norm > 1e-10 * original.max(f64::MIN_POSITIVE) && norm > 0.0 {
                r[(filled, j)] = norm;
                v.col_mut(filled).copy_from(col * (1.0 / norm));
            } else {
                let x = random_orthogonal(q, v.subcols(0, filled), rng);
                v.col_mut(filled).copy_from(&x);
            }
            filled += 1;
        }
    }
    (v, r)
}

/// A unit random vector orthogonal to the columns of `q` and `v`.
fn random_orthogonal(q: MatRef<'_, f64>, v: MatRef<'_, f64>, rng: &mut StdRng) -> faer::Col<f64> {
    loop {
        let mut x = faer::Col::<f64>::from_fn(q.nrows(), |_| rng.random_range(-1.0..1.0));
        for _ in 0..2 {
            for basis in [q, v] {
                let c = basis.transpose() * &x;
                x -= basis * &c;
            }
        }
        let norm = x.norm_l2();
        if norm > 1e-8 {
            return x * (1.0 / norm);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{grid_plane, icosphere};

    /// `‖L x − λ M x‖ / ‖M x‖` for every pair, and `max |XᵀMX − I|`.
    fn check_pairs(mesh: &TriMesh, pairs: &LaplacianEigenpairs) -> (f64, f64) {
        let l = cotangent_laplacian(mesh).unwrap();
        let m = lumped_mass_matrix(mesh);
        let x = &pairs.vectors;
        let lx = &l * x;
        let mut residual = 0.0f64;
        for j in 0..x.ncols() {
            let (mut r, mut s) = (0.0, 0.0);
            for i in 0..x.nrows() {
                let mx = m[i] * x[(i, j)];
                r += (lx[(i, j)] - pairs.values[j] * mx).powi(2);
                s += mx * mx;
            }
            residual = residual.max((r / s).sqrt() / pairs.values[j].abs().max(1.0));
        }
        let mut gram_error = 0.0f64;
        for a in 0..x.ncols() {
            for b in 0..x.ncols() {
                let g: f64 = (0..x.nrows()).map(|i| x[(i, a)] * m[i] * x[(i, b)]).sum();
                let expected = if a == b { 1.0 } else { 0.0 };
                gram_error = gram_error.max((g - expected).abs());
            }
        }
        (residual, gram_error)
    }

    #[test]
    fn sphere_spectrum_groups_into_spherical_harmonics() {
        let sphere = icosphere(4);
        // l = 0..4: multiplicities 1, 3, 5, 7, 9.
        let pairs = laplacian_eigenvectors(&sphere, 25).unwrap();
        let mut next = 0;
        for l in 0..5usize {
            let exact = (l * (l + 1)) as f64;
            for _ in 0..2 * l + 1 {
                let value = pairs.values[next];
                // Discretisation error of the subdivision-4 icosphere: 0.7 % at l = 4 (λ ≈ 19.87).
                assert!(
                    (value - exact).abs() <= 1e-2 * exact + 1e-8,
                    "λ{next} = {value}, l = {l}"
                );
                next += 1;
            }
        }
        let (residual, gram) = check_pairs(&sphere, &pairs);
        assert!(residual < 1e-6, "residual {residual}");
        assert!(gram < 1e-9, "XᵀMX − I: {gram}");
    }

    #[test]
    fn lanczos_matches_the_dense_solution() {
        // 642 vertices: above the dense limit, so the Lanczos path runs.
        let mesh = bumpy_sphere();
        let k = 40;
        let pairs = laplacian_eigenvectors(&mesh, k).unwrap();
        let (entries, sqrt_mass) = entries_and_sqrt_mass(&mesh);
        let (dense, _) = dense_eigenpairs(&entries, &sqrt_mass, k).unwrap();
        for (a, b) in pairs.values.iter().zip(&dense) {
            assert!((a - b).abs() < 1e-8 * b.max(1.0), "{a} vs {b}");
        }
        let (residual, gram) = check_pairs(&mesh, &pairs);
        assert!(residual < 1e-6 && gram < 1e-9, "{residual} {gram}");
    }

    #[test]
    fn square_with_boundary_has_neumann_spectrum() {
        // Unit square, free boundary: λ = π²(a² + b²) → 0, π², π², 2π², 4π², 4π².
        let plane = grid_plane(40, 40);
        let pairs = laplacian_eigenvectors(&plane, 6).unwrap();
        let pi2 = std::f64::consts::PI.powi(2);
        for (value, expected) in pairs.values.iter().zip([0.0, 1.0, 1.0, 2.0, 4.0, 4.0]) {
            assert!(
                (value - expected * pi2).abs() < 0.01 * pi2 * expected + 1e-8,
                "{value}"
            );
        }
    }

    #[test]
    fn two_components_give_two_zero_eigenvalues_and_unused_vertices_are_zero() {
        let (mut v, mut f, ..) = icosphere(3).into_parts();
        let offset = v.len() as u32;
        let shifted: Vec<_> = v
            .iter()
            .map(|p| [p[0] * 2.0 + 5.0, p[1] * 2.0, p[2] * 2.0])
            .collect();
        let faces: Vec<_> = f.iter().map(|t| t.map(|i| i + offset)).collect();
        v.extend(shifted);
        f.extend(faces);
        v.push([9.0; 3]);
        let mesh = TriMesh::new(v, f).unwrap();
        let pairs = laplacian_eigenvectors(&mesh, 6).unwrap();
        assert!(pairs.values[0].abs() < 1e-8 && pairs.values[1].abs() < 1e-8);
        // The big sphere (radius 2) has λ = l(l+1)/4: its l = 1 triple comes first.
        for value in &pairs.values[2..5] {
            assert!((value - 0.5).abs() < 0.01, "{value}");
        }
        assert_eq!(pairs.vectors[(mesh.vertex_count() - 1, 3)], 0.0);
        let (residual, gram) = check_pairs(&mesh, &pairs);
        assert!(residual < 1e-6 && gram < 1e-9, "{residual} {gram}");
    }

    #[test]
    fn cholesky_qr_is_used_when_well_conditioned_and_gram_schmidt_otherwise() {
        let mut rng = StdRng::seed_from_u64(7);
        let none = Mat::<f64>::zeros(5000, 0);
        let mut w = Mat::<f64>::from_fn(5000, 6, |_, _| rng.random_range(-1.0..1.0));
        let (v, r) = cholesky_qr(&w).expect("a random block is well conditioned");
        let identity = Mat::<f64>::identity(6, 6);
        assert!((v.transpose() * &v - &identity).norm_max() < 1e-13);
        assert!((&v * &r - &w).norm_max() < 1e-12);
        assert!((0..6).all(|j| (j + 1..6).all(|i| r[(i, j)] == 0.0) && r[(j, j)] > 0.0));
        // Column 5 equal to column 4 up to 1e-12: CholQR refuses, Gram-Schmidt replaces it.
        for i in 0..5000 {
            w[(i, 5)] = w[(i, 4)] * (1.0 + 1e-12);
        }
        assert!(cholesky_qr(&w).is_none());
        let (v, r) = orthonormalize(&mut w.clone(), none.as_ref(), 6, &mut rng);
        assert!((v.transpose() * &v - &identity).norm_max() < 1e-12);
        assert!(r[(5, 5)].abs() < 1e-8 * r[(4, 4)]);
        assert!((&v * &r - &w).norm_max() < 1e-9);
    }

    #[test]
    fn ritz_checks_are_spaced_by_the_extrapolated_residual() {
        // 3 decades in 48 vectors, 2 more to the tolerance of 1e-6: 32 (inside [24, 448/8 = 56]).
        assert_eq!(next_check_distance(Some((400, 1e-1)), (448, 1e-4), 24), 32);
        // Far from converged: at most size/8; close: at least a block.
        assert_eq!(next_check_distance(Some((400, 1e-2)), (448, 1e-3), 24), 56);
        assert_eq!(next_check_distance(Some((400, 1e-2)), (448, 1e-5), 24), 24);
        // No earlier check, or a residual that did not fall: size/8 (or a block if larger).
        assert_eq!(next_check_distance(None, (448, 1e-5), 24), 56);
        assert_eq!(next_check_distance(Some((400, 1e-6)), (448, 1e-5), 24), 56);
        assert_eq!(next_check_distance(None, (100, 1e-5), 24), 24);
    }

    #[test]
    fn same_result_for_any_thread_count() {
        // 10 242 vertices: several row blocks of the parallel products.
        let mesh = icosphere(5);
        let reference = laplacian_eigenvectors(&mesh, 20).unwrap();
        for threads in [1, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let again = pool.install(|| laplacian_eigenvectors(&mesh, 20).unwrap());
            assert_eq!(reference.values, again.values);
            assert_eq!(reference.vectors, again.vectors);
        }
    }

    /// The local entries of `L` and `M^{1/2}` of a one-component mesh.
    fn entries_and_sqrt_mass(mesh: &TriMesh) -> (Vec<Triplet<usize, usize, f64>>, Vec<f64>) {
        let l = cotangent_laplacian(mesh).unwrap();
        let entries = (0..l.ncols())
            .flat_map(|c| {
                let rows = l.symbolic().row_idx_of_col_raw(c).to_vec();
                let vals = l.val_of_col(c).to_vec();
                rows.into_iter()
                    .zip(vals)
                    .map(move |(r, v)| Triplet::new(r, c, v))
            })
            .collect();
        let sqrt_mass = lumped_mass_matrix(mesh).iter().map(|x| x.sqrt()).collect();
        (entries, sqrt_mass)
    }

    /// icosphere(3) with a radial bump: 642 vertices, above the dense limit.
    fn bumpy_sphere() -> TriMesh {
        let sphere = icosphere(3);
        let bumped: Vec<[f32; 3]> = sphere
            .vertices()
            .iter()
            .map(|p| {
                let r = 1.0 + 0.2 * (3.0 * p[0]).sin() * (2.0 * p[1]).cos();
                p.map(|x| x * r)
            })
            .collect();
        sphere.with_vertices(bumped).unwrap()
    }

    #[test]
    fn every_valid_shift_gives_the_smallest_pairs_and_a_shift_too_high_is_rejected() {
        let mesh = bumpy_sphere();
        let k = 40;
        let (entries, sqrt_mass) = entries_and_sqrt_mass(&mesh);
        let (dense, _) = dense_eigenpairs(&entries, &sqrt_mass, k + 1).unwrap();
        let null = null_vector(&sqrt_mass);
        // Valid: below zero (positive definite), and inside the spectrum below the midpoint of
        // λ₁ and λ_k (indefinite, the wanted on both sides).
        let midpoint = 0.5 * (dense[1] + dense[k]);
        for sigma in [-1e-6, 0.3 * dense[k - 1], 0.95 * midpoint] {
            let factor = shifted_factor(&entries, &sqrt_mass, sigma).unwrap();
            assert_eq!(factor.negative_eigenvalues().is_some(), sigma > 0.0);
            let subspace = shift_invert_subspace(&factor, &sqrt_mass, &null, k, sigma)
                .unwrap_or_else(|e| panic!("σ = {sigma}: {e}"));
            let (values, vectors) =
                refined_pairs(&entries, &sqrt_mass, &factor, &null, subspace).unwrap();
            for (a, b) in values.iter().zip(&dense) {
                assert!((a - b).abs() < 1e-8 * b.max(1.0), "σ = {sigma}: {a} vs {b}");
            }
            let gram = vectors.transpose() * &vectors - Mat::<f64>::identity(k, k);
            assert!(gram.norm_max() < 1e-9, "σ = {sigma}");
        }
        // Too high: the k nearest the shift leave out λ₁, and the inertia count says so.
        let sigma = 0.6 * dense[k];
        let factor = shifted_factor(&entries, &sqrt_mass, sigma).unwrap();
        let error = shift_invert_subspace(&factor, &sqrt_mass, &null, k, sigma).unwrap_err();
        assert!(
            error.to_string().contains("eigenvalues below it"),
            "{error}"
        );
    }

    #[test]
    fn refinement_removes_the_rounding_that_slivers_amplify() {
        // The bumpy sphere with every 7th vertex pulled almost onto a neighbour: sliver
        // triangles, masses down to ~1e-10 of the others, a huge ‖M^{-1/2} L M^{-1/2}‖.
        let mesh = bumpy_sphere();
        let mut vertices = mesh.vertices().to_vec();
        let mut moved = vec![false; vertices.len()];
        for face in mesh.triangles().iter().step_by(7) {
            let (a, b) = (face[0] as usize, face[1] as usize);
            if !moved[a] && !moved[b] {
                vertices[a] = std::array::from_fn(|i| {
                    vertices[b][i] + 1e-5 * (vertices[a][i] - vertices[b][i])
                });
                moved[a] = true;
            }
        }
        let mesh = mesh.with_vertices(vertices).unwrap();
        let k = 40;
        let (entries, sqrt_mass) = entries_and_sqrt_mass(&mesh);
        let null = null_vector(&sqrt_mass);
        let factor = shifted_factor(&entries, &sqrt_mass, -1e-8).unwrap();
        let subspace = shift_invert_subspace(&factor, &sqrt_mass, &null, k, -1e-8).unwrap();
        // ‖A y − λ y‖ of the Ritz vectors before and after the refinement.
        let worst = |values: &[f64], y: &Mat<f64>| {
            let ay = scaled_laplacian_product(&entries, &sqrt_mass, y);
            (1..k)
                .map(|j| {
                    (0..y.nrows())
                        .map(|i| (ay[(i, j)] - values[j] * y[(i, j)]).powi(2))
                        .sum::<f64>()
                        .sqrt()
                        / values[j]
                })
                .fold(0.0f64, f64::max)
        };
        let ritz: Vec<f64> = {
            let ay = scaled_laplacian_product(&entries, &sqrt_mass, &subspace);
            (0..k)
                .map(|j| {
                    (0..subspace.nrows())
                        .map(|i| subspace[(i, j)] * ay[(i, j)])
                        .sum()
                })
                .collect()
        };
        let before = worst(&ritz, &subspace);
        let (values, vectors) =
            refined_pairs(&entries, &sqrt_mass, &factor, &null, subspace).unwrap();
        let after = worst(&values, &vectors);
        assert!(after < 1e-6 && after < 1e-2 * before, "{before} → {after}");
    }

    #[test]
    fn invalid_requests_are_errors() {
        let sphere = icosphere(1);
        assert!(matches!(
            laplacian_eigenvectors(&sphere, 0),
            Err(Error::InvalidParameter { name: "k", .. })
        ));
        assert!(matches!(
            laplacian_eigenvectors(&sphere, 43),
            Err(Error::InvalidParameter { name: "k", .. })
        ));
        assert!(matches!(
            laplacian_eigenvectors(&TriMesh::default(), 1),
            Err(Error::Empty { .. })
        ));
        // k = #V works (dense path) and gives a full M-orthonormal basis.
        let pairs = laplacian_eigenvectors(&sphere, 42).unwrap();
        let (_, gram) = check_pairs(&sphere, &pairs);
        assert!(gram < 1e-9);
    }
}
