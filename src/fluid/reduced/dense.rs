//! Dense helpers of the reduced step ([`super::step`]): row-major matrix–vector products,
//! symmetric-axis folding, and Cholesky.

use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_upper_triangular_in_place};
use faer::{Accum, Mat, MatRef, Par};

use crate::fluid::FluidError;
use crate::tensor::{distinct_permutations, Tensor};

use super::induced::sorted_tuples;

/// `y = M x` for row-major `M` (rows × cols) with the rows split in two halves run by rayon
/// (the step's largest contraction, `Â ⊗₂ f̂`).
pub(super) fn matvec_split(m: &[f64], rows: usize, cols: usize, x: &[f64]) -> Vec<f64> {
    if rows < 1024 {
        return matvec(m, rows, cols, x);
    }
    let half = rows / 2;
    let (a, b) = m.split_at(half * cols);
    let (mut top, bottom) = rayon::join(|| matvec(a, half, cols, x), || matvec(b, rows - half, cols, x));
    top.extend(bottom);
    top
}

/// A tensor whose last `d` axes (length `m` each) are symmetric, as `rows × monomials`: one
/// column per sorted index tuple `i₁ ≤ … ≤ i_d`, its entry times the tuple's number of distinct
/// permutations, so that contracting with `Π x_{i_k}` per column equals the full contraction
/// with `x` on every symmetric axis. Returns the values and the tuples.
pub(super) fn fold_symmetric(data: &[f64], rows: usize, m: usize, d: usize) -> (Vec<f64>, Vec<Vec<usize>>) {
    let tuples = sorted_tuples(m, d);
    let nm = tuples.len();
    let block = m.pow(d as u32);
    let stride: Vec<usize> = (0..d).map(|k| m.pow((d - 1 - k) as u32)).collect();
    let mut out = vec![0.0; rows * nm];
    for (c, idx) in tuples.iter().enumerate() {
        let sorted: Vec<u32> = idx.iter().map(|&i| i as u32).collect();
        let mult = distinct_permutations(&sorted).len() as f64;
        let offset: usize = idx.iter().zip(&stride).map(|(i, s)| i * s).sum();
        for r in 0..rows {
            out[r * nm + c] = mult * data[r * block + offset];
        }
    }
    (out, tuples)
}

/// `y = M x` for row-major `M` (rows × cols).
pub(super) fn matvec(m: &[f64], rows: usize, cols: usize, x: &[f64]) -> Vec<f64> {
    let mut y = Mat::<f64>::zeros(rows, 1);
    let mr = MatRef::from_row_major_slice(m, rows, cols);
    let xr = MatRef::from_column_major_slice(x, cols, 1);
    matmul(y.as_mut(), Accum::Replace, mr, xr, 1.0, Par::Seq);
    (0..rows).map(|i| y[(i, 0)]).collect()
}

/// A row-major `r × c` tensor as a matrix.
pub(super) fn row_major(t: &Tensor, r: usize, c: usize) -> Mat<f64> {
    Mat::from_fn(r, c, |i, j| t.data()[i * c + j])
}

/// `AᵀB` of two row-major matrices with the same rows.
pub(super) fn transpose_times(a: &Tensor, b: &Tensor) -> Mat<f64> {
    let (n, ma, mb) = (a.shape()[0], a.shape()[1], b.shape()[1]);
    let mut out = Mat::<f64>::zeros(ma, mb);
    matmul(
        out.as_mut(),
        Accum::Replace,
        MatRef::from_row_major_slice(a.data(), n, ma).transpose(),
        MatRef::from_row_major_slice(b.data(), n, mb),
        1.0,
        Par::rayon(0),
    );
    out
}

/// Lower Cholesky factor of an SPD matrix (faer's blocked factorisation, one thread: these
/// matrices are a few hundred rows); refuses one that is not positive definite, naming it.
pub(super) fn cholesky(a: &Mat<f64>, what: &str) -> Result<Mat<f64>, FluidError> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::cholesky::llt::factor::{cholesky_in_place, cholesky_in_place_scratch};
    let n = a.nrows();
    let mut l = a.clone();
    let mut mem = MemBuffer::new(cholesky_in_place_scratch::<f64>(n, Par::Seq, Default::default()));
    let refused = |detail: String| {
        FluidError::State(format!(
            "{what} is not positive definite ({detail}): the reduced geometry or basis is degenerate"
        ))
    };
    if (0..n).any(|i| !a[(i, i)].is_finite()) {
        return Err(refused("a diagonal entry is not finite".into()));
    }
    cholesky_in_place(l.as_mut(), Default::default(), Par::Seq, MemStack::new(&mut mem), Default::default())
        .map_err(|e| refused(format!("{e:?}")))?;
    for j in 0..n {
        if !(l[(j, j)] > 0.0 && l[(j, j)].is_finite()) {
            return Err(refused(format!("pivot {j} of {n} is {:.3e}", l[(j, j)])));
        }
        for i in 0..j {
            l[(i, j)] = 0.0;
        }
    }
    Ok(l)
}

/// `x = (LLᵀ)⁻¹ b` for a lower Cholesky factor `L`.
pub(super) fn cholesky_solve(l: &Mat<f64>, b: &Mat<f64>) -> Mat<f64> {
    let mut x = b.clone();
    solve_lower_triangular_in_place(l.as_ref(), x.as_mut(), Par::Seq);
    solve_upper_triangular_in_place(l.transpose(), x.as_mut(), Par::Seq);
    x
}
