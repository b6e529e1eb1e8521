//! Dense helpers of the reduced step ([`super::step`]): row-major matrix–vector products,
//! symmetric-axis folding, and Cholesky.

use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_upper_triangular_in_place};
use faer::{Accum, Mat, MatRef, Par};

use crate::fluid::FluidError;
use crate::tensor::{distinct_permutations, Tensor};

use super::induced::sorted_tuples;

/// `y = M x` for a row-major `M` (rows × cols) stored in f32, accumulated in f64, the rows
/// split in two halves run by rayon: the step's largest contractions (`Â ⊗₂ f̂`, `Â_h ⊗₂ ĥ`),
/// which read their tensors whole every step and wait on memory (the bird's `Â_h` is 193² × 244
/// values), so f32 storage halves their time; the values' rounding (6·10⁻⁸ relative) is far
/// below the reduction's own error.
pub(super) fn matvec_f32_split(m: &[f32], rows: usize, cols: usize, x: &[f64]) -> Vec<f64> {
    if cols == 0 {
        return vec![0.0; rows];
    }
    let m = &m[..rows * cols];
    let rows_of = |m: &[f32]| -> Vec<f64> { m.chunks_exact(cols).map(|row| dot_f32(row, x)).collect() };
    if rows < 1024 {
        return rows_of(m);
    }
    let (a, b) = m.split_at(rows / 2 * cols);
    let (mut top, bottom) = rayon::join(|| rows_of(a), || rows_of(b));
    top.extend(bottom);
    top
}

/// `Σ a_j x_j` with f32 `a` widened to f64 ([`dot_f32_portable`]), compiled for AVX2 and FMA
/// too and chosen at run time where the processor has them (four widened values per
/// instruction instead of two).
fn dot_f32(a: &[f32], x: &[f64]) -> f64 {
    #[cfg(target_arch = "x86_64")]
    {
        if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma") {
            // SAFETY: the processor has AVX2 and FMA, checked just above.
            return unsafe { dot_f32_avx2(a, x) };
        }
    }
    dot_f32_portable(a, x)
}

/// [`dot_f32_portable`] compiled with AVX2 and FMA enabled.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn dot_f32_avx2(a: &[f32], x: &[f64]) -> f64 {
    dot_f32_portable(a, x)
}

/// `Σ a_j x_j` with f32 `a` widened to f64, in eight independent sums as
/// [`crate::tensor::dot`] sums f64 rows (kept apart: a generic version of that function,
/// widening each value, measured 20–30 % slower here).
#[inline(always)]
fn dot_f32_portable(a: &[f32], x: &[f64]) -> f64 {
    let mut acc = [0.0f64; 8];
    let (ac, xc) = (a.chunks_exact(8), x.chunks_exact(8));
    let tail: f64 = ac.remainder().iter().zip(xc.remainder()).map(|(&p, q)| f64::from(p) * q).sum();
    for (p, q) in ac.zip(xc) {
        for k in 0..8 {
            acc[k] += f64::from(p[k]) * q[k];
        }
    }
    acc.iter().sum::<f64>() + tail
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The f32 product (both halves, the eight sums and the tail, on whichever instruction set
    /// the processor picks) equals the plain f64 product of the same rounded values to f64
    /// rounding: rows past the split, columns not a multiple of eight.
    #[test]
    fn the_f32_product_is_the_f64_product_of_the_rounded_values() {
        let (rows, cols) = (1500, 29);
        let m: Vec<f32> = (0..rows * cols).map(|i| ((i * 7919 % 1000) as f32 - 500.0) / 300.0).collect();
        let x: Vec<f64> = (0..cols).map(|j| (j as f64 * 0.37).sin()).collect();
        let wide: Vec<f64> = m.iter().map(|&v| f64::from(v)).collect();
        let want = matvec(&wide, rows, cols, &x);
        let got = matvec_f32_split(&m, rows, cols, &x);
        let scale = want.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for (r, (a, b)) in got.iter().zip(&want).enumerate() {
            assert!((a - b).abs() <= 1e-14 * scale, "row {r}: {a} against {b}");
        }
        assert_eq!(matvec_f32_split(&m, 10, 0, &[]), vec![0.0; 10]);
    }
}
